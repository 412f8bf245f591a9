#pragma once
// What the SLAM layer (slam_graph.hpp) is told: keyframe selection, loop proposals and gating, landmark sightings,
// the incremental smoother's options, and the lifelong keyframe budget.  The daemon's `graph:` config section is
// these options plus the stage's own (daemon/engine/graph_stage_config.hpp).
#include "estimators/graph/incremental_options.hpp"
#include "estimators/keyframe/keyframe_selector.hpp"
#include "estimators/keyframe/keyframe_thinning.hpp"
#include "estimators/keyframe/loop_proposals.hpp"
#include "estimators/slam/frame_placement.hpp"

#include <map>
#include <optional>
#include <string>

namespace sextant::slam {

/// Landmark sightings: sightings with an id become point landmarks of the observing body and range/bearing factors
/// on its keyframes (sighting_anchor.hpp, sighting_gate.hpp).
struct LandmarkOptions {
  bool enabled = true;
  bool robust = true;                // the loops' kernel (SlamOptions::robust) applies to them, at their own width
                                     // (sighting_kernel_width_for)
  double gate_probability = 0.999;   // chi-square gate of a sighting of a known landmark against the estimate
  double gate_odometry_scale = 3.0;  // the odometry's standard deviations are taken this many times larger in the
                                     // gate (the odometry between keyframe and sighting; biases are not in it)
  int max_waiting = 256;             // sighting messages per body ahead of its odometry, kept until it gets there
};

/// Lifelong mode: a keyframe budget per kind of body.  When the graph of a kind of body holds more than its
/// `max_keyframes`, it is thinned to its `window` newest keyframes and one keyframe per place
/// (estimators/keyframe/keyframe_thinning.hpp), so its size follows the explored space, not the time run; a graph
/// within the budget is never touched.  The 3-D budget is smaller: a 3-D keyframe has twice the unknowns of a planar
/// one and its sightings three rows instead of two, and a rank update costs about the square of that
/// (bench/RESULTS.md, "Lifelong": the 3-D graph at 2000 keyframes replayed at 30x, at 1000 at 80x).
struct LifelongOptions {
  struct Budget {
    int max_keyframes = 2000;
    int window = 1000;  // the newest keyframes that stay whole (shared by the bodies of the kind)
  };
  bool enabled = true;
  Budget planar{2000, 1000};
  Budget spatial{1000, 500};
  KeyframeThinningOptions thinning;  // cell_size and heading_sector; its window is the budget's of the kind
  /// Where a thinning leaves each map frame's gauge (slam_graph_thinning.cpp, choose_anchors): true, on a settled
  /// keyframe at its current estimate when the root's first keyframe is no longer tied to the map by what stays, so
  /// the frame stays where the whole graph had it; false, always on the first keyframe, the frame re-estimated from
  /// what stays.  Daemons of one fleet that exchange contributions thin at their own moments, and frames held at
  /// each one's estimate of its moment differ by centimetres, so the fleet exchange sets it false
  /// (graph_config_reader.cpp): every daemon's frame is then the same keyframe's.
  bool hold_frame = true;
  const Budget& budget(bool planar_kind) const { return planar_kind ? planar : spatial; }
};

/// A fleet (slam_graph.hpp, "Fleet"): every body of the layer belongs to one fleet; each starts in a map frame of its
/// own and joins another body's frame when frame_placement.hpp's rule places it there.
struct FleetOptions {
  bool enabled = true;                     // false: every body is estimated alone, as separate robots
  std::map<int64_t, std::string> markers;  // landmark id -> the body whose origin a sighting of that id sees
  PlacementOptions placement;              // the joining rule
  // A sighting of a body at a time its odometry has not reached yet waits for it (at most max_pending per body) and
  // is anchored exactly, interpolated between the odometry poses around it.
  int max_pending = 256;  // robot sightings and loops between frames not yet joined, kept as evidence (oldest go)
  int join_every_keyframes = 5;  // placement tried at most this often per pair of frames without new evidence
  /// Inter-robot loop candidates (SlamListener::fleet_loop_proposed, with propose_loops): for each new keyframe, the
  /// nearest keyframe of every other body of its frame within this many metres (0: none).
  double proposal_radius = 2.0;
};

struct SlamOptions {
  KeyframeSelectorOptions keyframes;  // k1, k2 (motion magnitude, metres/radians combined) and the weights
  bool propose_loops = true;          // propose loop candidates for each new keyframe (SlamListener::loop_proposed)
  LoopProposalOptions proposals;      // n1 local, n2 random (-1: 2 n1), seed
  graph::RobustKernel robust = graph::RobustKernel::kDcs;  // on loop closures (and landmark sightings): none | huber |
                                                           // cauchy | dcs
  /// Huber/Cauchy delta or DCS phi.  nullopt ("auto"): per body kind, from the chi-square quantile of the loop
  /// residual's dimension at loop_gate_probability, q = chi2_d(p), d = 3 planar / 6 spatial (kernel_width_for).
  std::optional<double> kernel_width;
  double loop_gate_probability = 0.999;   // chi-square consistency gate of a loop against the current estimate
  double loop_gate_odometry_scale = 3.0;  // the odometry's standard deviations are taken this many times larger in the
                                          // gate (odometry covariances are optimistic: biases are not in them)
  /// m: a loop whose ends land through thinned keyframes with a larger standard deviation than this (loop_gate.hpp,
  /// landing_sigma) is refused (counted as rejected): the gate could not tell it from a match to another place.
  double loop_max_landing_sigma = 1.0;
  double loop_time_tolerance_s =
      1.0;  // a loop's times must be this close to keyframes' times (odometry bridges the gap)
  /// Loops about times a body's odometry has not reached yet wait for it, at most this many per body; one beyond
  /// is dropped and counted (SlamCounters::loops_waiting_dropped).  0: none waits.
  int max_waiting_loops = 256;
  /// Odometry poses kept per body to bridge loop times to keyframes (10 minutes at 50 Hz): memory per body is bounded
  /// at 64 bytes each.  A loop about an older time that is not a keyframe's own is counted as unmatched; with lifelong
  /// thinning such a loop would land on a thinned keyframe's anchor, weakened to little (planar 60-minute run:
  /// 30000 against 100000 left 1480 of 3556 loops unmatched and moved the graph's ATE from 14.3 to 13.8 mm, and the
  /// daemon's memory stops growing after 10 minutes instead of 33; bench/RESULTS.md, "Lifelong").
  int odometry_history = 30000;
  double min_increment_variance = 1e-10;  // floor of the increment covariance's eigenvalues (pose_covariance.hpp)
  /// Solve cadence, in data time, per map frame: with a period > 0 a frame's updates are made at most once per period
  /// for the local inputs, and what arrives in between enters with the next one (fuse's optimization_frequency, an
  /// iSAM2 front end's update per keyframe).  A fleet of N bodies in one frame then costs one update per period, not
  /// one per message of each body (8 simulated robots, 5 minutes: 63,793 updates and 34 s of replay at 0, 5,461
  /// and 20 s at 0.05; bench/RESULTS.md, "A simulated fleet in lifelong mode").  The owed update runs with the frame's
  /// first local input past the period, before a placement, a thinning or a gate reads an estimate that is not
  /// solved yet (a loop about a new keyframe, a landmark's second sighting), and at flush().  0 (the default): after
  /// every input, the freshest estimate; and bodies in separate frames that share a smoother never move each other's
  /// published poses, which an update made for one body's period cannot promise for the other's pending factors.
  double solve_period_s = 0;
  /// The incremental smoother's options (config key `smoother:`): relinearization thresholds and skip, wildfire,
  /// the rank-update budget, reordering and its spreading over updates.  Their defaults are IncrementalOptions'
  /// own (one source of truth).  `kernel` and `kernel_width` here are not used: the smoother's kernel is `robust`
  /// and its width kernel_width_for(), per kind of body.
  graph::IncrementalOptions smoother;
  LifelongOptions lifelong;
  LandmarkOptions landmarks;
  FleetOptions fleet;
};

/// The robust kernel's width for the loops of one kind of body (planar: x, y, yaw residuals, d = 3; spatial: d = 6).
/// The configured width if there is one; "auto" takes q = chi2_d(loop_gate_probability), the loop gate's quantile
/// (assoc::chi2_quantile, the exact inverse of the incomplete gamma function: 16.27 for d = 3 and 22.46 for d = 6 at
/// 0.999), so that a true loop keeps its full weight with that probability whatever its dimension:
///  - DCS phi = q (Agarwal et al., "Robust Map Optimization using Dynamic Covariance Scaling", ICRA 2013): the scale
///    min(1, 2 phi / (phi + chi2)) is 1 for chi2 <= phi, a gate that fades instead of cutting;
///  - Huber and Cauchy delta = sqrt(q) (their weights are functions of sqrt(chi2) / delta).
/// A fixed phi cannot serve both kinds: a 6-DOF residual's chi2 is on average twice a 3-DOF one's, and phi = 1 keeps a
/// true 6-DOF loop at its median chi2 (5.35) only (2 / 6.35)^2 = 0.10 of its weight (bench/RESULTS.md).
double kernel_width_for(const SlamOptions& options, bool planar);
/// The same for landmark sightings, which the smoother takes with a width of their own (add_factor's kernel_width):
/// a sighting's residual has d = 2 (range, bearing) on a planar body and d = 3 (range, azimuth, elevation) on a 3-D
/// one, and its gate is at landmarks.gate_probability, so "auto" takes q = chi2_d(landmarks.gate_probability), the
/// sighting gate's quantile (13.82 for d = 2 and 16.27 for d = 3 at 0.999; the loops' 16.27 and 22.46 left a wrong
/// sighting past the gate more weight than a wrong loop of the same probability); a configured width applies to
/// sightings too.
double sighting_kernel_width_for(const SlamOptions& options, bool planar);

}  // namespace sextant::slam
