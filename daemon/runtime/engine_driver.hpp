#pragma once
// The one path from a message's bytes to published outputs, shared by sextantd, `sextant replay` and the tests:
//
//   bytes on a channel --Intake--> event --route--> every stage that accepts it --emit--> Publisher --> raw sink
//                       (decode, validate,          (a StageHost per stage:         (the one rule of publication:
//                        time guard)                 forget, handle, recover)        no FusedPose at or before the
//                                                                                    last one of its body)
//
// What differs between a daemon and a replay is supplied from outside and nothing else:
//  - the clock: each message comes with its Arrival (the bus's clocks live, the log's time in replay), so the time
//    guard's idle expiry and resync decide the same for the same data;
//  - the lanes to the stages: kStageThreads gives each stage a bounded queue and a thread (StageRunner, the
//    daemon); kInline calls each stage at once, in stage order (tests); kPipelined runs the graph's stages on a
//    second thread beside the others and publishes what kInline would, in its order (replay: pipelined_lanes.hpp).
//    All go through StageHost.
//  - the raw sink: the LCM bus, or a log / memory.
// Forgetting is decided here and only here: the bodies whose odometry stream the intake expired are forgotten by
// every stage before the next event, and the first message of a body whose clock was re-synchronised carries the
// order to forget that body first (QueuedEvent::forget_first), in order with its earlier messages.  A stage that
// forgets a body has the publisher forget that body's last FusedPose time for the stage's estimator, after the
// stage's earlier outputs.
#include "daemon/config/daemon_config.hpp"
#include "daemon/engine/engine.hpp"
#include "daemon/runtime/channel_stats.hpp"
#include "daemon/runtime/intake.hpp"
#include "daemon/runtime/pipelined_lanes.hpp"
#include "daemon/runtime/publisher.hpp"
#include "daemon/runtime/stage_host.hpp"
#include "daemon/runtime/stage_runner.hpp"

#include <chrono>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace sextant::runtime {

enum class StageLanes {
  kInline,        // each stage called at once, in stage order, on the caller's thread (replay, tests)
  kStageThreads,  // each stage on its own thread behind a bounded queue (sextantd); start() and drain() apply
  /// The graph and graph pose stages on a worker thread, the others on the caller's, every event to both in order;
  /// the outputs, forgets and on_handled calls of kInline, in kInline's order, on the caller's thread, a little later
  /// (settle() waits for them).  Without a graph stage, or with only graph stages: kInline.
  kPipelined,
};

struct DriverOptions {
  bool live = false;  // the intake checks stamps against the wall clock and may evict (sextantd)
  StageLanes lanes = StageLanes::kInline;
  /// A Trajectory's solve time is wall-clock time; replay publishes 0 there so that its outputs depend on the data
  /// alone (the report keeps the stages' timing separately).
  bool zero_solve_time = false;
  Intake::RejectHook on_reject;  // every rejection, for rate-limited logging
  /// Every event the intake accepted, before it goes to the stages (on the caller's thread).
  std::function<void(const engine::Event&)> on_accepted;
  /// Every output the publisher published (called on the emitting stage's thread).
  std::function<void(const engine::Output&)> on_published;
  /// kInline, kPipelined: called after each stage handled an event, with the stage's index and its processing time
  /// (ms).
  std::function<void(size_t stage, double ms)> on_handled;
};

class EngineDriver {
 public:
  /// `engine` must outlive the driver.  `raw` receives every encoded message the publisher sends.
  EngineDriver(const config::DaemonConfig& config, engine::Engine& engine, Publisher::RawSink raw,
               DriverOptions options);
  ~EngineDriver();
  EngineDriver(const EngineDriver&) = delete;
  EngineDriver& operator=(const EngineDriver&) = delete;

  /// One message of `channel` that arrived at `arrival`: decoded, checked, and routed to every stage that accepts
  /// it (a full queue is a drop on the channel).  True when the intake accepted it.
  bool input(const std::string& channel, const void* data, size_t size, Arrival arrival);
  /// The clock of a fleet's exchange (engine.graph.fleet.exchange) moving without data: a FleetControl without a
  /// sender at `arrival`'s wall time for the graph stage, so that its heartbeats and repairs go on while no data
  /// arrives (sextantd calls it a few times a second from the thread that calls input()); nothing when the exchange
  /// is off.
  void tick(Arrival arrival);
  /// kStageThreads: starts the stage threads.
  void start();
  /// kPipelined: returns when every event routed so far has been handled by every stage and what it did delivered
  /// (published, on_published, on_handled); the stages are idle until the next input, so their state may be read.
  /// Other lanes: nothing to wait for.
  void settle();
  /// End of input.  kInline: every stage finishes now.  kStageThreads: intake stops, each stage handles what is
  /// queued until `deadline` (what is left then is discarded, counted and returned), finishes, and its thread ends.
  int64_t finish(std::chrono::steady_clock::time_point deadline = std::chrono::steady_clock::time_point::max());

  /// Each stage's status (kInline, kPipelined: latency empty and queue sizes 0).
  std::vector<StageStatus> stage_status();
  /// kStageThreads: the runners (the state directory saves each stage between two of its events).
  std::vector<std::unique_ptr<StageRunner>>& runners() { return runners_; }

  Intake& intake() { return intake_; }
  const Intake& intake() const { return intake_; }
  ChannelStats& stats() { return stats_; }
  const ChannelStats& stats() const { return stats_; }
  Publisher& publisher() { return publisher_; }
  const Publisher& publisher() const { return publisher_; }
  engine::Engine& engine() { return engine_; }

 private:
  // Publishes one output through the publication rule; tells on_published when it was published.
  void publish(engine::Output output);
  // The bodies the intake expired: every stage forgets them before its next event.
  void forget_expired();
  // Hands an accepted event to every stage that accepts it.
  void route(const std::string& channel, QueuedEvent queued);
  void make_lanes(const config::DaemonConfig& config);
  // kPipelined: the lanes on two threads (their hosts attached by make_lanes); kInline instead when the engine has no
  // stages for one of them.
  void make_pipelined_lanes();
  // kPipelined: one captured thing a stage did, done now (published, forgotten by the publisher, counted).
  void deliver(StageCapture& capture);

  engine::Engine& engine_;
  DriverOptions options_;
  ChannelStats stats_;
  Intake intake_;
  Publisher publisher_;
  engine::Emit emit_;
  std::vector<std::unique_ptr<StageHost>> hosts_;      // kInline, kPipelined
  std::unique_ptr<PipelinedLanes> pipelined_;          // kPipelined with stages on both threads
  std::vector<std::string> estimators_;                // per stage: its estimator (the publisher's forget)
  std::vector<std::unique_ptr<StageRunner>> runners_;  // kStageThreads
  std::string tick_channel_;                           // fleet_control when the exchange is on (tick)
  std::vector<int64_t> processed_;                     // kInline, kPipelined: events per stage
};

}  // namespace sextant::runtime
