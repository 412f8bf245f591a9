#pragma once
// The graph back end on the bus: an adapter between the engine's events and the SLAM layer
// (estimators/slam/slam_graph.hpp, where keyframes, loop gating, sighting anchoring and gating, time resolution and
// lifelong thinning are described and done).  This stage
//  - turns Odometry, LoopClosure and LandmarkSightings into the layer's inputs (a body is an odometry source);
//  - turns what the layer reports into outputs: MATCH_REQUESTS for its loop proposals (request ids numbered here),
//    after every update the map -> odometry correction for GraphPoseStage (graph_correction.hpp) and TRAJECTORY at
//    its own rate (trajectory_feed.hpp: new and moved keyframes, a rolling snapshot, bounded messages), and each map
//    frame's landmarks on LANDMARK_MAP at the same rate (landmark_map_t.lcm; chunks of kMaxLandmarksPerMessage);
//  - handles one event at a time and knows no threads: in the daemon a body's odometry may reach it in batches
//    (daemon/runtime/odometry_batcher.hpp), handed to `handle` one message at a time as replay does;
//  - counts what it does itself (GraphStageCounters) beside the layer's counters (slam_counters.hpp).
#include "daemon/engine/fleet_exchange.hpp"
#include "daemon/engine/graph_correction.hpp"
#include "daemon/engine/graph_stage_config.hpp"
#include "daemon/engine/stage.hpp"
#include "daemon/engine/trajectory_feed.hpp"
#include "estimators/slam/slam_graph.hpp"

#include <atomic>
#include <map>
#include <memory>
#include <optional>
#include <utility>

namespace sextant::engine {

/// A landmark of the graph's map (slam::SlamLandmark: id, position in the body's map frame, sightings in the graph).
using GraphLandmark = slam::SlamLandmark;

/// What the graph stage counts itself (the layer's counts are slam::SlamCounters).
struct GraphStageCounters {
  int64_t match_requests = 0;             // MATCH_REQUESTS published
  int64_t trajectory_messages = 0;        // TRAJECTORY messages published
  int64_t trajectory_keyframe_bytes = 0;  // their keyframes (72 bytes each) and removed ids (8 bytes each)
  int64_t corrections_refused = 0;        // solves whose newest keyframe was not finite or not PSD: not published
  int64_t landmark_map_messages = 0;      // LANDMARK_MAP messages published
};

class GraphStage final : public Stage {
 public:
  GraphStage(const GraphConfig& config, std::shared_ptr<GraphCorrectionBoard> corrections);
  StageKind kind() const override { return StageKind::kGraph; }
  bool accepts(const Event& e) const override {
    return std::holds_alternative<Odometry>(e) || std::holds_alternative<LoopClosure>(e) ||
           (config_.landmarks.enabled && std::holds_alternative<LandmarkSightings>(e)) ||
           (config_.fleet_exchange.enabled &&
            (std::holds_alternative<FleetContributions>(e) || std::holds_alternative<FleetControl>(e)));
  }
  void handle(const Event& e, const Emit& emit) override;
  /// The last TRAJECTORY publication of every body: every keyframe that moved at all since it was published.
  void finish(const Emit& emit) override;
  /// Refactorizes the smoothers from their graphs (a failed update can leave a factor out of step with the graph).
  void recover(const Event& /*failed*/) override { slam_.rebuild(); }
  /// A smoother's rebuild under way (a batch of factors, a refactorization, lifelong thinning, the save's canonical
  /// form) ends after its Gauss-Newton iteration under way (IncrementalOptions::interrupt), and so do later ones;
  /// counted (`solves_interrupted`: the smoothers' interrupted rebuilds).  Thread-safe.
  void interrupt() override { interrupt_.store(true); }
  Counters counters() const override;
  /// The state directory: the stage's counters and next request id, the layer's state (SlamGraph::save: graphs,
  /// bodies, waiting loops and sightings, counters), then per body its TRAJECTORY feed and map -> odometry correction.
  void save(archive::ArchiveWriter& w) override;
  void load(archive::ArchiveReader& r) override;
  /// Drops the body with its map (SlamGraph::forget), its feed and correction.
  void forget(const std::string& source) override;
  /// The fleet exchange checks each local contribution with `check` before numbering it (Outbox::set_wire_check),
  /// now and after a load; nothing without the exchange.
  void set_fleet_wire_check(fleet::Outbox::WireCheck check);

  /// The smoother of the planar bodies or of the 3-D ones (nullptr before the first such body).
  const graph::IncrementalSmoother* smoother(bool planar) const { return slam_.smoother(planar); }
  /// The keyframes of a body (optimized poses), oldest first.
  std::vector<Keyframe> keyframes(const std::string& source) const;
  /// The landmarks of a body (optimized positions), by id.
  std::vector<GraphLandmark> landmarks(const std::string& source) const { return slam_.landmarks(source); }
  /// The size of the graphs now (every body): keyframes and landmarks in them, factors in the smoothers.
  int64_t graph_keyframes() const { return slam_.graph_keyframes(); }
  int64_t graph_landmarks() const { return slam_.graph_landmarks(); }
  int64_t graph_factors() const { return slam_.graph_factors(); }
  /// Rebuilds of the current smoothers ended by interrupt().
  int64_t solves_interrupted() const;

 private:
  /// The layer's reports turned into outputs for one handle() call (graph_stage.cpp).
  class Outputs;
  /// What TRAJECTORY needs of a body between calls.
  struct Feed {
    TrajectoryFeed feed;
    int64_t newest_utime = 0;  // of the last optimization, for the final publication
  };
  /// TRAJECTORY messages of a body when its feed is due (or `flush`): chi2 and the keyframe list are computed only then.
  void publish_trajectory(const std::string& source, Feed& f, int64_t utime, int solves, bool flush, const Emit& emit);
  Feed& feed_of(const std::string& source);
  /// chi2 of the smoother `source` is in, evaluated at most once per trajectory period of data time (or `flush`).
  double chi2_of(const std::string& source, int64_t utime, bool flush);
  /// LANDMARK_MAP of `frame` when due (the trajectory's rate) or `flush`; a frame that joined another since its last
  /// publication is published once empty.
  void publish_map(const std::string& frame, int64_t utime, bool flush, const Emit& emit);
  static constexpr size_t kMaxLandmarksPerMessage = 1024;  // 36 bytes each: under one 64 KB datagram

  GraphConfig config_;
  std::shared_ptr<GraphCorrectionBoard> corrections_;
  std::atomic<bool> interrupt_{false};  // read by the smoothers (their options' interrupt): before slam_
  slam::SlamGraph slam_;
  std::map<std::string, Feed> feeds_;
  std::map<std::string, int64_t> maps_published_;  // frame -> utime of its last LANDMARK_MAP
  std::pair<std::optional<int64_t>, double> chi2_[2];
  /// engine.graph.fleet.exchange (null when off): the local bodies' contributions numbered and sent, the other
  /// members' applied in their streams' order (fleet_exchange.hpp).  Its clock is the newest time the stage has seen:
  /// the data's and the fleet messages', and a live daemon's ticks (a FleetControl without a sender, see handle).
  std::unique_ptr<fleet::FleetExchange> exchange_;
  fleet::Outbox::WireCheck wire_check_;  // set_fleet_wire_check's, handed again to an exchange a load replaces
  int64_t exchange_now_ = 0;
  /// A fleet event through the exchange: what it makes due applied to the graph and sent.
  void exchange(const Event& e, Outputs& out, const Emit& emit);
  /// While a restarted exchange fetches the tails of this daemon's own streams (FleetExchange::fetching), the events
  /// that would make or apply contributions wait here (at most kMaxHeldBack: the wait ends when it is full), so that
  /// the own contributions go on after the tail, numbered and with keyframe ids after it; handled in their order
  /// when the wait ends.  Not saved (a state saved meanwhile is the one loaded, without the tail: the next start
  /// fetches it again).
  bool held_back(const Event& e) const;
  void release_held(const Emit& emit);
  static constexpr size_t kMaxHeldBack = 8192;  // a few MB of events; 2 s of inputs are a few hundred
  std::vector<Event> held_;
  int64_t next_request_id_ = 0;
  GraphStageCounters counters_;
};

}  // namespace sextant::engine
