#pragma once
// The graph back end: keyframe pose-graph SLAM with landmarks on the incremental smoother
// (estimators/graph/incremental_smoother.hpp).
// Per body (odometry source):
//  - keyframes: each odometry pose is classified by KeyframeSelector (too close / keyframe / implausible jump,
//    counted); a keyframe becomes a pose variable linked to the previous keyframe by the odometry between them, with
//    the composed increment covariance as information;
//  - after a real jump (reanchor_after consistent implausible poses in a row: the odometry lost track and resumed
//    elsewhere) the selector re-anchors (keyframes_reanchored): the new keyframe is linked to the last one before the
//    jump by the odometry across it, its covariance inflated by the jump's own size (jump_covariance in the .cpp).
//    Why one graph and not a new segment: a new segment would need its own gauge (a fixed first keyframe and its own
//    map frame, so FUSED_POSE would jump to another frame) and loops across the two could not join them without
//    moving a fixed pose; with a weak edge the map frame stays, the fused pose continues from the odometry's guess,
//    and the first loops across the jump pull the new segment into place;
//  - loop proposals: for each new keyframe the LoopProposer's pairs go out as MatchRequests (keyframe ids are the
//    body's keyframe indices, 0, 1, 2, ...);
//  - loop closures (answers and unsolicited ones) are tied to keyframes by id or by time — a time between keyframes
//    is moved to the nearest keyframe through the odometry recorded between them (z' = (O_kf^-1 O_t) z (O_t'^-1 O_kf'),
//    O the odometry poses) — then checked against the
//    current estimate with a chi-square gate whose covariance is the loop's plus the odometry's between the two
//    keyframes (an upper bound of the estimate's relative uncertainty), and added with a robust kernel (DCS by
//    default, its width per kind of body: kernel_width_for in graph_stage_config.hpp); rejected loops are counted;
//    A loop about a time the body's odometry has not reached yet waits (at most 256 per body) and is tried again
//    when the odometry gets there;
//  - landmark sightings (LandmarkSightings with a landmark id; sightings without an id, -1, are counted as
//    sightings_without_id and left to the filters' association) become point variables of the observing body (one
//    per id and body: each body's map has its own frame) and range/bearing factors (range/azimuth/elevation for 3-D
//    bodies; PointObservationFactor, estimators/graph/factor.hpp).  A sighting is taken at an odometry time, not at a
//    keyframe time; it becomes a keyframe-relative observation: the factor is on the newest keyframe K at or before
//    the sighting, with the sensor offset D S (D = O_K^-1 O_t the odometry from K to the sighting, interpolated on
//    the group between the two odometry messages around t; S the sensor in the body) and the odometry's uncertainty
//    folded into the measurement's: R' = R + J_D Sigma_D J_D', J_D = dh/dD (right perturbation).  A sighting ahead of
//    the odometry waits (at most max_waiting messages per body) for the odometry message after it, where Sigma_D is
//    exact (the covariance since K plus the interpolated part of the increment); a sighting the odometry has already
//    passed takes the covariance to the next keyframe, or to the latest odometry (a little more than its own).
//    Several sightings in one odometry interval share D's error but enter as independent (slightly optimistic).
//    A sighting of a known landmark is gated against the current estimate: d2 = e' S^-1 e with
//    S = R + k^2 J_D Sigma_D J_D' + J_K P_K J_K' + J_p P_p J_p' (P: marginal covariances of keyframe and landmark,
//    their correlation ignored, which makes S larger for a landmark mapped from the same poses), chi-square at
//    gate_probability; rejected sightings are counted.  Accepted ones enter with the smoother's robust kernel, so a
//    mis-identified landmark that passes the gate is down-weighted rather than bending the map, at a width of their
//    own (sighting_kernel_width_for in graph_stage_config.hpp: with "auto" the sighting gate's chi-square quantile
//    of the sighting's dimension, 13.82 for a 2-D sighting and 16.27 for a 3-D one, not the loops' 16.27 and 22.46).
//    A landmark's first sighting initializes it and is not gated: a wrong first id plants a wrong landmark, that later true sightings
//    are gated against (limitation).  Landmark positions after each update: landmarks(source).
//  - after every update: the map -> odometry correction for GraphPoseStage; TRAJECTORY at its own rate
//    (trajectory_feed.hpp: new and moved keyframes, a rolling snapshot, bounded messages).
//  - the stage handles one event at a time and knows no threads: in the daemon a body's odometry may reach it in
//    batches (daemon/runtime/odometry_batcher.hpp), handed to `handle` one message at a time as replay does.
// The first keyframe of a body is held fixed at its odometry pose: the map frame is the odometry frame at the
// body's first keyframe, as for dead reckoning.
#include "daemon/engine/graph_correction.hpp"
#include "daemon/engine/graph_stage_config.hpp"
#include "daemon/engine/stage.hpp"
#include "daemon/engine/trajectory_feed.hpp"
#include "estimators/graph/incremental_smoother.hpp"

#include <map>
#include <memory>

namespace sextant::engine {

/// A landmark of the graph's map: its id (the sightings' landmark id), position in the body's map frame (metres; z = 0
/// for planar bodies) and how many of its sightings are in the graph.
struct GraphLandmark {
  int64_t id = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  int64_t sightings = 0;
};

class GraphStage final : public Stage {
 public:
  GraphStage(const GraphConfig& config, std::shared_ptr<GraphCorrectionBoard> corrections);
  std::string_view name() const override { return "graph"; }
  bool accepts(const Event& e) const override {
    return std::holds_alternative<Odometry>(e) || std::holds_alternative<LoopClosure>(e) ||
           (config_.landmarks.enabled && std::holds_alternative<LandmarkSightings>(e));
  }
  void handle(const Event& e, const Emit& emit) override;
  /// The last TRAJECTORY publication of every body: every keyframe that moved at all since it was published.
  void finish(const Emit& emit) override;
  /// Refactorizes the smoothers from their graphs (a failed update can leave a factor out of step with the graph).
  void recover(const Event& /*failed*/) override {
    for (auto& s : smoothers_)
      if (s) s->rebuild();
  }
  Counters counters() const override;
  /// The state directory (graph_stage_state.cpp): both graphs (variables at their estimates, factors with their
  /// kernels), every body's keyframes, thinned keyframes, odometry history, waiting loops and sightings, landmarks,
  /// selector and TRAJECTORY feed, the map -> odometry corrections, next ids and counters.  Saving refactorizes each
  /// smoother from its graph (rebuild) right after writing it, and forgets the sighting gate's cached marginals: a
  /// stage restored from the file does the same from the same graph, so both continue identically.
  void save(archive::ArchiveWriter& w) override;
  void load(archive::ArchiveReader& r) override;
  /// Drops the body with its map: its keyframes, landmarks and their factors leave the smoother of its kind (rebuilt
  /// from the other bodies' variables and factors, graph_stage_state.cpp), its waiting loops and sightings, feed and
  /// correction go.
  void forget(const std::string& source) override;

  /// The smoother of the planar bodies or of the 3-D ones (nullptr before the first such body).
  const graph::IncrementalSmoother* smoother(bool planar) const { return smoothers_[planar ? 1 : 0].get(); }
  /// The keyframes of a body (optimized poses), oldest first.
  std::vector<Keyframe> keyframes(const std::string& source) const;
  /// The landmarks of a body (optimized positions), by id.
  std::vector<GraphLandmark> landmarks(const std::string& source) const;
  /// The size of the graphs now (every body): keyframes and landmarks in them, factors in the smoothers.
  int64_t graph_keyframes() const;
  int64_t graph_landmarks() const;
  int64_t graph_factors() const;

 private:
  struct KeyframeNode {
    int64_t id = 0;       // the body's keyframe id: 0, 1, 2, ... in order of creation (MATCH_REQUESTS, TRAJECTORY)
    int64_t utime = 0;
    int variable = -1;
    SE3 odom;
    Matrix6 odom_covariance = Matrix6::Zero();
    Matrix6 edge_covariance = Matrix6::Zero();  // of the odometry from the previous keyframe
    SE3 edge;                                   // that odometry (composed across thinned keyframes)
  };
  /// A keyframe that lifelong thinning took out of the graph: what resolving a loop to its time needs.
  struct ThinnedKeyframe {
    int64_t id = 0, utime = 0;
    SE3 odom;
  };
  /// Thinned records kept per body (72 bytes each, 7.2 MB): at the simulated runs' 6 keyframes per second, the last
  /// 4.6 hours of thinned keyframe times stay resolvable; older ones are forgotten, so memory stays bounded.
  static constexpr size_t kMaxThinnedRecords = 100000;
  struct Body {
    bool planar = false;
    graph::IncrementalSmoother* smoother = nullptr;  // smoothers_[planar]
    KeyframeSelector selector;
    int64_t last_utime = 0;
    SE3 last_odom;
    Matrix6 last_odom_covariance = Matrix6::Zero();
    Matrix6 since_keyframe = Matrix6::Zero();  // covariance of the odometry since the last keyframe
    std::vector<KeyframeNode> keyframes;        // in the graph, by id (and time)
    std::map<int64_t, size_t> by_utime;         // -> position in keyframes
    std::vector<ThinnedKeyframe> thinned;       // taken out by lifelong thinning, by id (and time); the newest
                                                // kMaxThinnedRecords
    int64_t next_keyframe_id = 0;
    std::vector<std::pair<int64_t, SE3>> odometry;  // recent odometry poses (bounded), for loops between keyframes
    std::vector<LoopClosure> early_loops;  // loops about times this body's odometry has not reached yet (bounded)
    std::vector<LandmarkSightings> early_sightings;  // sightings ahead of the odometry, in time order (bounded)
    struct Landmark {
      int variable = -1;
      int64_t sightings = 0;
    };
    std::map<int64_t, Landmark> landmarks;  // by landmark id
    TrajectoryFeed feed;                    // what TRAJECTORY carries for this body
    int64_t newest_utime = 0;               // of the last optimization, for the final publication
  };
  /// Where a sighting is taken from: keyframe K, the odometry D from K to the sighting and D's covariance.
  struct SightingAnchor {
    size_t keyframe = 0;
    SE3 motion;
    Matrix6 covariance = Matrix6::Zero();
  };
  void on_odometry(const Odometry& o, const Emit& emit);
  static void remember_odometry(Body& b, int64_t utime, const SE3& pose, size_t history);
  void on_keyframe_candidate(const Odometry& o, Body& b, const SE3& odom, const Emit& emit);
  /// A keyframe candidate at `odom` that cannot enter the graph (its odometry edge's covariance cannot be inverted,
  /// or the smoother refuses it): counted (odometry_edges_rejected); the selector goes back to the body's last keyframe
  /// in the graph, so the next keyframe is measured from that one and its edge, which spans the dropped pose,
  /// accumulates the odometry covariance from there.
  void drop_keyframe(Body& b);
  void on_loop(const LoopClosure& l, const Emit& emit);
  /// Where a loop's end lands: a keyframe of the graph (position in Body::keyframes), the odometry motion from it to
  /// the loop's time, and that motion's covariance (zero when the time is the keyframe's or bridged by recorded
  /// odometry within the tolerance; an upper bound when the end's keyframe was thinned).
  struct LoopEnd {
    size_t keyframe = 0;
    SE3 motion;
    Matrix6 covariance = Matrix6::Zero();
  };
  std::optional<LoopEnd> resolve(const Body& b, int64_t keyframe_id, int64_t utime) const;
  void on_sightings(const LandmarkSightings& s, const Emit& emit);
  /// The anchor of a sighting at a time the odometry has reached, after the body's first keyframe (nullopt: older
  /// than the odometry history).
  std::optional<SightingAnchor> anchor_of(const Body& b, int64_t utime) const;
  void add_sightings(const LandmarkSightings& s, Body& b, const SightingAnchor& anchor, const Emit& emit);
  void optimize_and_publish(const std::string& source, Body& b, int64_t utime, const Emit& emit);
  /// TRAJECTORY messages of a body when its feed is due (or `flush`): chi2 and the keyframe list are computed only then.
  void publish_trajectory(const std::string& source, Body& b, int64_t utime, int solves, bool flush, const Emit& emit);
  graph::IncrementalSmoother& smoother_for(bool planar);

  /// What a factor of a smoother is, kept beside it (FactorTag per factor, in the smoother's order) so that lifelong
  /// thinning can rebuild the graph: odometry edges are recomposed, loops and sightings carried over.
  enum class FactorRole { kOdometry, kLoop, kSighting };
  struct FactorTag {
    FactorRole role = FactorRole::kOdometry;
    bool robust = false;
    std::optional<double> kernel_width;
  };
  /// Adds a factor to the body's smoother and its tag (throws what the smoother throws, and then adds no tag).
  void add_factor(Body& b, std::unique_ptr<graph::Factor> factor, FactorRole role, bool robust, std::optional<double> width);
  /// Lifelong mode (graph_stage_lifelong.cpp): when the keyframes of a kind of body exceed its lifelong budget (max_keyframes), the
  /// smoother of that kind is rebuilt with the keyframes keyframes_to_keep() keeps (estimators/keyframe/
  /// keyframe_thinning.hpp): odometry composed across the thinned ones, loops and sightings of thinned keyframes
  /// dropped, landmarks left without sightings dropped.
  void maybe_thin(bool planar);
  /// The factor of an odometry edge between two keyframe variables, from the edge's covariance over sextant's tangent;
  /// nullptr when that covariance cannot be inverted (it can only come from a sender's malformed covariances).
  static std::unique_ptr<graph::Factor> odometry_factor(bool planar, int from, int to, const SE3& edge, const Matrix6& covariance);
  void thin(bool planar);
  /// The counters the state directory keeps (graph_stage_state.cpp).
  std::vector<int64_t*> saved_counters();

  GraphConfig config_;
  std::shared_ptr<GraphCorrectionBoard> corrections_;
  LoopProposer proposer_;
  /// One smoother per kind of body, [0] 3-D and [1] planar, created with the first such body: the bodies' graphs
  /// share no variable, and the robust kernel's width depends on the loops' dimension (kernel_width_for), which is
  /// the smoother's own width (the loops take it; sightings bring theirs to add_factor).
  std::unique_ptr<graph::IncrementalSmoother> smoothers_[2];
  std::vector<FactorTag> factor_tags_[2];  // per smoother, per factor
  /// Marginal covariances for the sighting gate, per smoother and variable: (updates_ when computed, marginal).
  static constexpr int64_t kGateMarginalUpdates = 25;
  std::map<int, std::pair<int64_t, Eigen::MatrixXd>> gate_marginals_[2];
  Eigen::MatrixXd gate_marginal(const Body& b, int variable);
  int64_t keyframes_since_thinning_[2] = {0, 0};
  std::map<std::string, Body> bodies_;
  int64_t next_variable_id_ = 0, next_request_id_ = 0;
  double chi2_gate_planar_ = 0, chi2_gate_spatial_ = 0, sighting_gate_planar_ = 0, sighting_gate_spatial_ = 0;
  double sighting_width_planar_ = 0, sighting_width_spatial_ = 0;  // sighting_kernel_width_for
  int64_t keyframes_ = 0, keyframes_rejected_ = 0, keyframes_reanchored_ = 0, requests_ = 0, loops_accepted_ = 0, loops_rejected_ = 0,
          loops_unmatched_ = 0, loops_unknown_source_ = 0, optimizer_failures_ = 0, rebuilds_ = 0,
          relinearized_ = 0, out_of_order_ = 0, bad_edges_ = 0;
  int64_t landmarks_ = 0, sightings_accepted_ = 0, sightings_rejected_ = 0, sightings_without_id_ = 0,
          sightings_unknown_source_ = 0, sightings_before_keyframe_ = 0, sightings_unmatched_ = 0,
          sightings_malformed_ = 0, sightings_dropped_ = 0;
  double last_update_ms_ = 0;
  int64_t trajectory_messages_ = 0, trajectory_bytes_ = 0, updates_ = 0;
  int64_t thinnings_ = 0, thinning_failures_ = 0, keyframes_thinned_ = 0, loops_thinned_ = 0, sightings_thinned_ = 0,
          landmarks_thinned_ = 0, loops_on_thinned_ = 0;
  int64_t thinning_us_ = 0, thinning_us_max_ = 0, thinning_solve_us_ = 0;  // wall clock of the last / longest thinning
};

}  // namespace sextant::engine
