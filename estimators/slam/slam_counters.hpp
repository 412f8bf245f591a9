#pragma once
// What the SLAM layer (slam_graph.hpp) has counted since it started (restored with its state): one struct, so that
// the daemon's status lists them and the state directory keeps them from one place.
#include <cstdint>

namespace sextant::slam {

struct SlamCounters {
  int64_t updates = 0;               // smoother updates (every keyframe, accepted loop and message of sightings)
  int64_t optimizer_failures = 0;    // updates (or refactorizations after forgetting a body) that failed
  int64_t rebuilds = 0;              // updates that reordered and refactorized the system, and refactorizations on save
  int64_t relinearized_factors = 0;  // summed over updates
  int64_t keyframes = 0;             // keyframes added to the graph
  int64_t keyframes_rejected = 0;    // implausible odometry poses (KeyframeSelector)
  int64_t keyframes_reanchored = 0;  // keyframes after a real jump, linked across it by a weak edge
  int64_t odometry_out_of_order = 0;               // odometry messages not newer than the body's previous one (dropped)
  int64_t odometry_edges_rejected = 0;             // keyframes dropped: their odometry edge could not enter the graph
  int64_t loops_accepted = 0, loops_rejected = 0;  // by the consistency gate (or refused by the smoother)
  int64_t loops_unmatched = 0;                     // an end not tied to a keyframe, or both ends on the same keyframe
  int64_t loops_unknown_source = 0;                // about a body without odometry
  int64_t loops_on_thinned = 0;  // accepted or not, an end landed through a thinned keyframe (widened)
  // Loops ahead of their body's odometry: waiting now (all bodies), and dropped at SlamOptions::max_waiting_loops.
  // Not saved: the waiting ones are counted again from the bodies on load, the dropped ones start from 0.
  int64_t loops_waiting = 0, loops_waiting_dropped = 0;
  int64_t landmarks = 0;                                   // landmarks created
  int64_t sightings_accepted = 0, sightings_rejected = 0;  // by the sighting gate
  int64_t sightings_without_id = 0;                        // left to the filters' association
  int64_t sightings_unknown_source = 0, sightings_before_keyframe = 0, sightings_unmatched = 0;
  int64_t sightings_malformed = 0;  // a bad value, a planar flag unlike the body's, or refused by the smoother
  int64_t sightings_dropped = 0;    // waiting for the odometry beyond LandmarkOptions::max_waiting
  int64_t thinnings = 0, thinning_failures = 0;
  // Fleet: frames joined; robot sightings and inter-robot loops added as factors, kept as evidence, left out as
  // outliers of a placement or dropped beyond FleetOptions::max_pending; robot sightings that could not be placed
  // (the seen body unknown, of another kind, without keyframes or its odometry too far behind) or of the observer
  // itself.
  int64_t fleet_joins = 0, fleet_sightings = 0, fleet_loops = 0, fleet_pending = 0, fleet_outliers = 0;
  int64_t fleet_pending_dropped = 0, fleet_sightings_unplaced = 0, fleet_self_sightings = 0;
  // Contributions of remote bodies (SlamGraph::apply): applied; refused (about a local body, a keyframe that does not
  // follow the body's newest, an anchor on a keyframe not in the graph, a value the smoother refuses); waiting for
  // another body's keyframe, and dropped from that wait beyond FleetOptions::max_pending.
  int64_t fleet_contributions_applied = 0, fleet_contributions_refused = 0, fleet_contributions_waiting = 0;
  int64_t fleet_contributions_dropped = 0;
  int64_t fleet_joins_remote = 0;   // joins applied as another graph decided them (FrameJoin), within fleet_joins
  int64_t fleet_joins_refused = 0;  // such decisions that could not apply here
  int64_t fleet_remote_inputs = 0;  // inputs about a remote body, refused (its owner's daemon has its sensors)
  int64_t keyframes_thinned = 0, loops_thinned = 0, sightings_thinned = 0, landmarks_thinned = 0;
  // Wall clock (not saved): the last update, the last and the longest thinning, the last thinning's solve.
  double last_update_ms = 0;
  int64_t thinning_us_last = 0, thinning_us_max = 0, thinning_solve_us_last = 0;

  /// The counters the state directory keeps, in their saved order (the wall-clock figures are not among them).
  template <class Archive, class Self>
  static void saved(Archive& a, Self& c) {
    a(c.updates)(c.optimizer_failures)(c.rebuilds)(c.relinearized_factors)(c.keyframes)(c.keyframes_rejected)(
        c.keyframes_reanchored)(c.odometry_out_of_order)(c.odometry_edges_rejected)(c.loops_accepted)(c.loops_rejected)(
        c.loops_unmatched)(c.loops_unknown_source)(c.loops_on_thinned)(c.landmarks)(c.sightings_accepted)(
        c.sightings_rejected)(c.sightings_without_id)(c.sightings_unknown_source)(c.sightings_before_keyframe)(
        c.sightings_unmatched)(c.sightings_malformed)(c.sightings_dropped)(c.thinnings)(c.thinning_failures)(
        c.keyframes_thinned)(c.loops_thinned)(c.sightings_thinned)(c.landmarks_thinned)(c.fleet_joins)(
        c.fleet_sightings)(c.fleet_loops)(c.fleet_pending)(c.fleet_outliers)(c.fleet_pending_dropped)(
        c.fleet_sightings_unplaced)(c.fleet_self_sightings)(c.fleet_contributions_applied)(
        c.fleet_contributions_refused)(c.fleet_contributions_waiting)(c.fleet_contributions_dropped)(
        c.fleet_remote_inputs)(c.fleet_joins_remote)(c.fleet_joins_refused);
  }
};

}  // namespace sextant::slam
