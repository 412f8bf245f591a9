#pragma once
// Keyframe pose-graph SLAM with landmarks on the incremental smoother (estimators/graph/incremental_smoother.hpp), for
// any number of bodies, from plain inputs (slam_inputs.hpp).  The daemon's graph stage adapts it to the bus
// (daemon/engine/graph_stage.hpp); a program can call it directly.
//
// Per body (named by a string, e.g. the odometry source):
//  - keyframes (add_odometry): each odometry pose is classified by KeyframeSelector (too close / keyframe /
//    implausible jump, counted); a keyframe becomes a pose variable linked to the previous keyframe by the odometry
//    between them, with the composed increment covariance (estimators/lie/pose_covariance.hpp) as information.  The
//    first keyframe is held fixed at its odometry pose: the map frame is the odometry frame at the body's first
//    keyframe, as for dead reckoning.  A keyframe whose edge cannot enter the graph (a covariance that cannot be
//    inverted, or a value the smoother refuses) is dropped and counted; the selector goes back to the last keyframe
//    in the graph, so the next edge spans the dropped pose;
//  - after a real jump (KeyframeSelector's kReanchored: the odometry lost track and resumed elsewhere) the new keyframe
//    is linked to the last one before the jump by the odometry across it, its covariance inflated by the jump's own
//    size (jump_covariance.hpp).  One graph, not a new segment: a new segment would need its own gauge and map frame,
//    and loops across the two could not join them without moving a fixed pose; with a weak edge the map frame stays
//    and the first loops across the jump pull the new segment into place;
//  - loop proposals: for each new keyframe the LoopProposer's pairs go to SlamListener::loop_proposed (keyframe ids
//    are the body's keyframe indices 0, 1, 2, ...);
//  - loop closures (add_loop): tied to keyframes by id or by time (keyframe_track.hpp), gated against the current
//    estimate (loop_gate.hpp) and added with the robust kernel (DCS by default, its width per kind of body:
//    kernel_width_for); a loop about a time the odometry has not reached waits (at most 256 per body);
//  - landmark sightings (add_sightings): sightings with an id become point variables of the observing body (one per
//    id and body: each body's map has its own frame) and range/bearing factors on the keyframe before them
//    (sighting_model.hpp), gated when the landmark is known; sightings ahead of the odometry wait (at most
//    LandmarkOptions::max_waiting messages) for the odometry message after them, where the anchor's covariance is
//    exact (the covariance since the keyframe plus the interpolated part of the increment);
//  - lifelong mode (slam_graph_thinning.cpp): over a kind of body's keyframe budget the graph is thinned to the places
//    it needs.
// One smoother per kind of body (planar, 3-D), created with the first such body: the bodies' graphs share no
// variable, and the robust kernel's width depends on the loops' dimension.  Every smoother update is reported to the
// listener, in order, while its estimates are current.
#include "estimators/archive/binary_archive.hpp"
#include "estimators/graph/incremental_smoother.hpp"
#include "estimators/keyframe/keyframe_selector.hpp"
#include "estimators/keyframe/loop_proposals.hpp"
#include "estimators/slam/keyframe_track.hpp"
#include "estimators/slam/slam_counters.hpp"
#include "estimators/slam/slam_inputs.hpp"
#include "estimators/slam/slam_options.hpp"

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace sextant::slam {

/// A keyframe of the graph: its id, time and current estimate in the body's map frame.
struct KeyframeEstimate {
  int64_t id = 0, utime = 0;
  SE3 pose;
};

/// A landmark of the graph's map: its id (the sightings' landmark id), position in the body's map frame (metres; z = 0
/// for planar bodies) and how many of its sightings are in the graph.
struct SlamLandmark {
  int64_t id = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  int64_t sightings = 0;
};

/// What the layer reports while it works (each call on the caller's thread, inside add_odometry / add_loop /
/// add_sightings, in the order things happen).
class SlamListener {
 public:
  virtual ~SlamListener() = default;
  /// A smoother update of `body` succeeded; `utime` is the newest time it covers (the newest keyframe's, or the
  /// keyframe's just added).  The estimates (keyframes(), newest_keyframe()) are this update's.
  virtual void updated(const std::string& body, int64_t utime, const graph::IncrementalStatus& status) = 0;
  /// A loop candidate for the new keyframe `a` (newest first) against the earlier keyframe `b`.
  virtual void loop_proposed(const std::string& body, int64_t utime, const KeyframeEstimate& a,
                             const KeyframeEstimate& b, bool random) = 0;
};

class SlamGraph {
 public:
  /// Throws std::invalid_argument for bad keyframe thresholds or loop proposal options.
  explicit SlamGraph(const SlamOptions& options);

  /// An odometry message of `body` (a new body starts with it; planar taken from it).  Older-or-equal times than the
  /// body's last are counted (odometry_out_of_order) and dropped.
  void add_odometry(const std::string& body, const OdometryInput& odometry, SlamListener& listener);
  /// A loop closure of `body` (see above).
  void add_loop(const std::string& body, const LoopInput& loop, SlamListener& listener);
  /// Landmark sightings of `body` (see above); nothing when landmarks are disabled.
  void add_sightings(const std::string& body, const SightingsInput& sightings, SlamListener& listener);
  /// Drops the body with its map: its keyframes, landmarks and their factors leave the smoother of its kind (rebuilt
  /// from the other bodies' variables and factors), its waiting loops and sightings go.
  void forget(const std::string& body);
  /// Refactorizes the smoothers from their graphs (after a failure the caller recovers from).
  void rebuild();

  /// The keyframe track of a body (nullptr: unknown body).
  const KeyframeTrack* track(const std::string& body) const;

  const SlamOptions& options() const { return options_; }
  const SlamCounters& counters() const { return counters_; }
  std::vector<std::string> bodies() const;
  /// The smoother of the planar bodies or of the 3-D ones (nullptr before the first such body).
  const graph::IncrementalSmoother* smoother(bool planar) const { return smoothers_[planar ? 1 : 0].get(); }
  /// The keyframes of a body (estimates), oldest first; empty for an unknown body.
  std::vector<KeyframeEstimate> keyframes(const std::string& body) const;
  /// The landmarks of a body (estimates), by id.
  std::vector<SlamLandmark> landmarks(const std::string& body) const;
  /// The newest keyframe of a body with its estimate and marginal covariance (6x6; a planar body's at x, y, yaw;
  /// zero when not determined).  The body must have a keyframe.
  struct NewestKeyframe {
    const TrackKeyframe* keyframe = nullptr;
    SE3 estimate;
    Matrix6d covariance = Matrix6d::Zero();
  };
  NewestKeyframe newest_keyframe(const std::string& body) const;
  /// chi2 of the smoother a body's graph is in.
  double chi2(const std::string& body) const;
  /// The size of the graphs now (every body): keyframes and landmarks in them, factors in the smoothers.
  int64_t graph_keyframes() const;
  int64_t graph_landmarks() const;
  int64_t graph_factors() const;

  /// The state (slam_graph_state.cpp): both graphs (variables at their estimates, factors with their kernels), every
  /// body's track, selector, waiting loops and sightings and landmarks, next ids and counters.  Saving refactorizes
  /// each smoother from its graph (rebuild) right after writing it, and forgets the sighting gate's cached marginals:
  /// a layer restored from the bytes does the same from the same graph, so both continue identically.  load() throws
  /// std::logic_error into a used layer and archive::ArchiveError for bytes that do not describe a consistent state.
  void save(archive::ArchiveWriter& w);
  void load(archive::ArchiveReader& r);

 private:
  /// What a factor of a smoother is, kept beside it (one tag per factor, in the smoother's order) so that lifelong
  /// thinning and forgetting can rebuild the graph: odometry edges are recomposed, loops and sightings carried over.
  enum class FactorRole { kOdometry, kLoop, kSighting };
  struct FactorTag {
    FactorRole role = FactorRole::kOdometry;
    bool robust = false;
    std::optional<double> kernel_width;
  };
  struct Landmark {
    int variable = -1;
    int64_t sightings = 0;
  };
  struct Body {
    bool planar = false;
    graph::IncrementalSmoother* smoother = nullptr;  // smoothers_[planar]
    KeyframeSelector selector;
    KeyframeTrack track;
    std::vector<LoopInput> early_loops;           // about times the odometry has not reached yet (bounded)
    std::vector<SightingsInput> early_sightings;  // ahead of the odometry, in time order (bounded)
    std::map<int64_t, Landmark> landmarks;        // by landmark id
  };

  Body& body_for(const std::string& name, bool planar);
  graph::IncrementalSmoother& smoother_for(bool planar);
  /// Adds a factor to the body's smoother and its tag (throws what the smoother throws, and then adds no tag).
  void add_factor(Body& b, std::unique_ptr<graph::Factor> factor, FactorRole role, bool robust,
                  std::optional<double> width);
  SE3 estimate(const Body& b, int variable) const;
  void on_keyframe_candidate(const std::string& name, Body& b, const OdometryInput& o, SlamListener& listener);
  /// A keyframe candidate that cannot enter the graph (its odometry edge's covariance cannot be inverted, or the
  /// smoother refuses it): counted; the selector goes back to the body's last keyframe in the graph, so the next
  /// keyframe is measured from that one and its edge, which spans the dropped pose, accumulates from there.
  void drop_keyframe(Body& b);
  void propose_loops(const std::string& name, const Body& b, int64_t utime, SlamListener& listener);
  /// One smoother update for `b`, counted and reported when it succeeds.
  void update(const std::string& name, Body& b, int64_t utime, SlamListener& listener);
  /// The sightings of one message at `anchor` (slam_graph_sightings.cpp).
  void add_anchored_sightings(const std::string& name, Body& b, const SightingsInput& s, const TrackPoint& anchor,
                              SlamListener& listener);
  /// Marginal covariances for the sighting gate, reused for kGateMarginalUpdates updates.
  Eigen::MatrixXd gate_marginal(const Body& b, int variable);
  /// Lifelong thinning (slam_graph_thinning.cpp): over the kind's budget, rebuild the smoother of that kind with the
  /// keyframes keyframes_to_keep() keeps (estimators/keyframe/keyframe_thinning.hpp): odometry composed across the
  /// thinned ones, loops and sightings of thinned keyframes dropped, landmarks left without sightings dropped.
  void maybe_thin(bool planar);
  void thin(bool planar);
  /// thin's steps (slam_graph_thinning.cpp), on the plan they fill in turn.
  struct ThinningPlan;
  bool choose_kept_keyframes(ThinningPlan& p);
  void choose_kept_factors(ThinningPlan& p);
  void rebuild_smoother(ThinningPlan& p);
  void commit_thinning(ThinningPlan& p);

  SlamOptions options_;
  LoopProposer proposer_;
  std::unique_ptr<graph::IncrementalSmoother> smoothers_[2];  // [0] 3-D, [1] planar
  std::vector<FactorTag> factor_tags_[2];                     // per smoother, per factor
  static constexpr int64_t kGateMarginalUpdates = 25;
  std::map<int, std::pair<int64_t, Eigen::MatrixXd>>
      gate_marginals_[2];  // per variable: (updates when computed, marginal)
  int64_t keyframes_since_thinning_[2] = {0, 0};
  std::map<std::string, Body> bodies_;
  int64_t next_variable_id_ = 0;
  double loop_gate_[2] = {0, 0}, sighting_gate_[2] = {0, 0};  // chi-square thresholds, [0] 3-D, [1] planar
  double sighting_width_[2] = {0, 0};                         // sighting_kernel_width_for
  SlamCounters counters_;
};

}  // namespace sextant::slam
