#include "daemon/runtime/daemon.hpp"

#include "daemon/engine/engine.hpp"
#include "daemon/runtime/input_router.hpp"
#include "daemon/runtime/intake.hpp"
#include "daemon/runtime/publisher.hpp"
#include "daemon/runtime/raw_subscription.hpp"
#include "daemon/runtime/recorder.hpp"
#include "daemon/runtime/shared_graph_corrections.hpp"
#include "daemon/runtime/stage_runner.hpp"
#include "daemon/runtime/state_directory.hpp"
#include "daemon/runtime/status_report.hpp"
#include "daemon/runtime/udp_drops.hpp"

#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>

#include <chrono>
#include <filesystem>
#include <map>
#include <memory>
#include <thread>

namespace sextant::runtime {
namespace {

using Clock = std::chrono::steady_clock;

// At most one log line per (channel, reason) per period; the lines in between are counted and mentioned.
class RateLimitedLog {
 public:
  explicit RateLimitedLog(double period_s) : period_(period_s) {}
  void warn(const std::string& channel, const std::string& reason, const std::string& message) {
    auto& e = entries_[channel + "/" + reason];
    const auto now = Clock::now();
    if (e.last.time_since_epoch().count() != 0 && std::chrono::duration<double>(now - e.last).count() < period_) {
      ++e.suppressed;
      return;
    }
    if (e.suppressed > 0)
      spdlog::warn("rejected ({}): {} [+{} similar since the last report]", reason, message, e.suppressed);
    else
      spdlog::warn("rejected ({}): {}", reason, message);
    e.last = now;
    e.suppressed = 0;
  }

 private:
  struct Entry {
    Clock::time_point last{};
    int64_t suppressed = 0;
  };
  double period_;
  std::map<std::string, Entry> entries_;
};

}  // namespace

std::string bus_failure_help(const std::string& url) {
  return "cannot start LCM on '" + (url.empty() ? std::string("the default URL (udpm://239.255.76.67:7667)") : url) +
         "'.\n"
         "  LCM's UDP multicast needs a route for 224.0.0.0/4. On a single machine:\n"
         "    sudo ip link set lo multicast on && sudo ip route add 224.0.0.0/4 dev lo\n"
         "  or run everything inside a private network namespace:\n"
         "    sudo unshare --net sh -c 'ip link set lo up; ip route add 224.0.0.0/4 dev lo; exec sextantd ...'\n"
         "  or pass another provider with --lcm-url (e.g. 'udpm://239.255.76.67:7667?ttl=0', 'memq://').";
}

namespace {

// The graph stage's odometry is batched per body (engine.graph.coalesce_odometry): it keeps each body's state apart,
// so batching (which keeps each body's order but not the order across bodies) changes nothing it computes.  The
// other stages see every message in arrival order (a filter may fuse several sources of one body).
std::optional<OdometryBatcherOptions> odometry_batching(const engine::Stage& stage, const engine::EngineConfig& config) {
  if (stage.kind() != engine::StageKind::kGraph || !config.graph.coalesce_odometry) return std::nullopt;
  OdometryBatcherOptions o;
  o.max_batch = static_cast<size_t>(config.graph.odometry_batch_max);
  o.max_waiting_per_body = static_cast<size_t>(config.graph.odometry_waiting_max);
  o.max_waiting = static_cast<size_t>(config.graph.odometry_waiting_total_max);
  return o;
}

}  // namespace

int run_daemon(const config::DaemonConfig& cfg, const std::atomic<bool>& stop) {
  lcm::LCM lcm(cfg.lcm_url);
  if (!lcm.good()) {
    spdlog::error("{}", bus_failure_help(cfg.lcm_url));
    return kExitBus;
  }

  // The graph stage and the graph pose stage run on two threads: their correction board is guarded.
  auto engine = std::make_unique<engine::Engine>(cfg.engine, std::make_shared<SharedGraphCorrections>());
  // The state directory: the stages continue from the saved state (state_directory.hpp).
  const std::string state_path = cfg.state_dir.empty() ? std::string() : state_file_path(cfg.state_dir);
  if (!state_path.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(cfg.state_dir, ec);
    if (ec) {
      spdlog::error("--state-dir {}: cannot create it: {}", cfg.state_dir, ec.message());
      return kExitState;
    }
    std::vector<engine::Stage*> stages;
    for (auto& s : engine->stages()) stages.push_back(s.get());
    try {
      if (restore_stages(state_path, cfg.engine_fingerprint, stages))
        spdlog::info("state restored from {}", state_path);
      else
        spdlog::info("no state in {}: starting fresh; state is saved there every {} s", cfg.state_dir, cfg.state_period_s);
    } catch (const StateFileError& e) {
      if (!cfg.discard_bad_state) {
        spdlog::error("bad state file: {}\n  Move it away, or start with --discard-bad-state to set it aside and start "
                      "fresh.", e.what());
        return kExitState;
      }
      try {
        const std::string aside = set_state_file_aside(state_path);
        spdlog::warn("bad state file: {}; set aside as {} (--discard-bad-state): starting fresh", e.what(), aside);
      } catch (const StateFileError& e2) {
        spdlog::error("{}", e2.what());
        return kExitState;
      }
      // The stages may have been partly restored.
      engine = std::make_unique<engine::Engine>(cfg.engine, std::make_shared<SharedGraphCorrections>());
    }
  }
  const std::string primary = engine->primary_estimator();
  Publisher publisher(cfg.channels, cfg.name, primary,
                      [&lcm](const std::string& channel, const std::vector<uint8_t>& bytes, int64_t) {
                        lcm.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
                      },
                      // Last FusedPose times per estimator channel and body: the bodies are bounded by max_sources.
                      static_cast<size_t>(std::max(cfg.max_sources, 1)) * 8);
  publisher.measure_lag([] {
    return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
  });
  const engine::Emit emit = [&publisher](engine::Output o) { publisher.publish(o); };

  std::vector<std::unique_ptr<StageRunner>> runners;
  for (auto& stage : engine->stages())
    runners.push_back(std::make_unique<StageRunner>(*stage, static_cast<size_t>(cfg.queue_capacity), emit,
                                                    odometry_batching(*stage, cfg.engine)));

  // A body a stage forgets (idle, or its clock re-synchronised) is forgotten by the publisher for that stage's
  // estimator too, on the stage's thread after its earlier outputs.
  for (size_t i = 0; i < runners.size(); ++i)
    if (const std::string estimator(engine->stages()[i]->estimator()); !estimator.empty())
      runners[i]->on_forget([&publisher, estimator](const std::string& source) { publisher.forget(estimator, source); });

  ChannelStats stats;
  RateLimitedLog log(cfg.log_rate_limit_s);
  Intake intake(stats, [&log](const std::string& c, const std::string& r, const std::string& m) { log.warn(c, r, m); },
                intake_options(cfg, /*live=*/true));
  const auto& ch = cfg.channels;
  intake.add_channel(ch.full(ch.odometry), InputKind::kOdometry);
  intake.add_channel(ch.full(ch.landmarks), InputKind::kLandmarks);
  intake.add_channel(ch.full(ch.bearings), InputKind::kBearings);
  intake.add_channel(ch.full(ch.loop_closures), InputKind::kLoopClosures);

  std::unique_ptr<Recorder> recorder;
  if (!cfg.record.empty()) {
    try {
      recorder = std::make_unique<Recorder>(cfg.record, 65536);
    } catch (const std::exception& e) {
      spdlog::error("--record: {}", e.what());
      return kExitRuntime;
    }
    if (recorder->path() != cfg.record)
      spdlog::warn("--record: {} exists and is kept; recording to {}", cfg.record, recorder->path());
  }

  // The intake's own counters, copied out by the LCM thread for the status thread (the intake is not thread-safe).
  struct IntakeCounters {
    std::atomic<int64_t> resyncs{0}, sources{0}, expired{0}, evicted{0};
  } intake_counters;

  // The LCM thread: every message on the bus is recorded (when asked) and, on an input channel, decoded and routed.
  struct Handler {
    Intake& intake;
    std::vector<std::unique_ptr<StageRunner>>& runners;
    ChannelStats& stats;
    Recorder* recorder;
    IntakeCounters& counters;
    // Nothing a message does may end the LCM thread: what escapes below is counted as an "internal" rejection.
    void on_message(const lcm_recv_buf_t& rbuf, const std::string& channel) {
      try {
        route(rbuf, channel);
      } catch (const std::exception& e) {
        stats.rejected(channel, "internal", channel + ": " + e.what());
      }
    }
    void route(const lcm_recv_buf_t& rbuf, const std::string& channel) {
      const auto received = Clock::now();
      if (recorder != nullptr) {
        const auto* b = static_cast<const uint8_t*>(rbuf.data);
        recorder->record(LogRecord{rbuf.recv_utime, channel, std::vector<uint8_t>(b, b + rbuf.data_size)});
      }
      route_input(intake, runners, stats, channel, rbuf.data, rbuf.data_size, received);
      if (intake.time_resyncs() != counters.resyncs.load()) {
        counters.resyncs = intake.time_resyncs();
        spdlog::warn("{} (time_resyncs: {}; every stage forgets the body)", intake.last_resync(), intake.time_resyncs());
      }
      counters.sources = static_cast<int64_t>(intake.sources());
      counters.expired = intake.sources_expired();
      counters.evicted = intake.sources_evicted();
    }
  } handler{intake, runners, stats, recorder.get(), intake_counters};
  // LCM keeps 30 undelivered messages per subscription by default and silently drops beyond that; our own
  // bounded queues do the counting, so give LCM's queue room for bursts.
  lcm_subscription_set_queue_capacity(subscribe_raw(lcm, ".*", &handler), cfg.queue_capacity * 8);

  for (auto& r : runners) r->start();
  spdlog::info("sextantd '{}' running on {}; stages: {}; primary estimator: {}", cfg.name,
               cfg.lcm_url.empty() ? "the default LCM URL" : cfg.lcm_url, runners.size(),
               primary.empty() ? "none" : primary);

  struct StateCounters {
    std::atomic<int64_t> saves{0}, failures{0}, bytes{0}, save_us{0};
  } state_counters;
  auto save_state = [&]() -> bool {
    try {
      const StateSave s = save_stages(state_path, cfg.engine_fingerprint, runners);
      if (state_counters.saves.fetch_add(1) == 0)
        spdlog::info("state saved to {}: {} bytes, {:.1f} ms from the stages, {:.1f} ms to write", state_path, s.bytes,
                     s.collect_ms, s.write_ms);
      state_counters.bytes = static_cast<int64_t>(s.bytes);
      state_counters.save_us = static_cast<int64_t>(1000 * (s.collect_ms + s.write_ms));
      return true;
    } catch (const std::exception& e) {
      const int64_t n = ++state_counters.failures;
      if (n <= 10 || (n & (n - 1)) == 0) spdlog::error("state not saved ({} failure(s) so far): {}", n, e.what());
      return false;
    }
  };

  const auto started = Clock::now();
  const int64_t drops_at_start = udp_receive_drops().value_or(0);
  StatusReport report(cfg.name);
  auto publish_status = [&] {
    std::vector<StageStatus> stage_status;
    for (auto& r : runners) stage_status.push_back(r->status());
    engine::Counters runtime_counters{{"fused_pose_not_monotonic", publisher.not_monotonic()},
                                      {"fused_pose_sources", static_cast<int64_t>(publisher.fused_pose_sources())},
                                      {"fused_pose_sources_forgotten", publisher.fused_pose_sources_forgotten()},
                                      {"fused_pose_sources_evicted", publisher.fused_pose_sources_evicted()},
                                      {"time_resyncs", intake_counters.resyncs.load()},
                                      {"sources", intake_counters.sources.load()},
                                      {"sources_expired", intake_counters.expired.load()},
                                      {"sources_evicted", intake_counters.evicted.load()}};
    if (const auto drops = udp_receive_drops()) runtime_counters.push_back({"udp_receive_drops", *drops - drops_at_start});
    const Publisher::Lag lag = publisher.take_lag();
    runtime_counters.push_back({"publish_lag_us", lag.last_us});
    runtime_counters.push_back({"publish_lag_us_max", lag.max_us});
    if (lag.max_us > 1'000'000)
      spdlog::warn("published up to {:.1f} s behind real time since the last status (a stall, or a backlog)", lag.max_us * 1e-6);
    if (!state_path.empty()) {
      runtime_counters.push_back({"state_saves", state_counters.saves.load()});
      runtime_counters.push_back({"state_save_failures", state_counters.failures.load()});
      runtime_counters.push_back({"state_bytes", state_counters.bytes.load()});
      runtime_counters.push_back({"state_save_us", state_counters.save_us.load()});
    }
    if (recorder) {
      runtime_counters.push_back({"recorded", recorder->written()});
      runtime_counters.push_back({"record_dropped", recorder->dropped()});
      runtime_counters.push_back({"record_failed", recorder->failed() ? 1 : 0});
    }
    publisher.publish(report.build(std::chrono::duration<double>(Clock::now() - started).count(), stats.snapshot(),
                                   stage_status, runtime_counters, publisher.counts(), publisher.bytes()));
  };

  std::atomic<bool> intake_stopped{false};
  std::thread status_thread([&] {
    auto next = Clock::now();
    const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(cfg.status_period_s));
    while (!intake_stopped.load()) {
      next += period;
      while (!intake_stopped.load() && Clock::now() < next) std::this_thread::sleep_for(std::chrono::milliseconds(20));
      if (!intake_stopped.load()) {
        try {
          publish_status();
        } catch (const std::exception& e) {
          spdlog::error("status: {}", e.what());
        }
      }
    }
  });

  // Periodic saves on a thread of their own: each stage is saved between two of its events (with_stage).
  std::thread state_thread;
  if (!state_path.empty())
    state_thread = std::thread([&] {
      auto next = Clock::now();
      const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(cfg.state_period_s));
      while (!intake_stopped.load()) {
        next += period;
        while (!intake_stopped.load() && Clock::now() < next) std::this_thread::sleep_for(std::chrono::milliseconds(20));
        if (!intake_stopped.load()) save_state();
      }
    });

  int rc = kExitOk;
  while (!stop.load()) {
    // A signal interrupts the poll (EINTR) and makes handleTimeout return -1: that is a shutdown, not a failure.
    if (lcm.handleTimeout(100) < 0 && !stop.load()) {
      spdlog::error("LCM handle failed; stopping. {}", bus_failure_help(cfg.lcm_url));
      rc = kExitBus;
      break;
    }
  }
  intake_stopped = true;
  spdlog::info("shutting down: draining {} stage queue(s) (at most {} s)", runners.size(), cfg.drain_timeout_s);
  for (auto& r : runners) r->stop_intake();
  const auto deadline =
      Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(cfg.drain_timeout_s));
  for (auto& r : runners)
    if (const int64_t left = r->drain_and_stop(deadline); left > 0)
      spdlog::warn("stage '{}': {} queued event(s) discarded at the drain timeout ({} s)", r->status().name, left,
                   cfg.drain_timeout_s);
  status_thread.join();
  if (state_thread.joinable()) state_thread.join();
  if (!state_path.empty()) {
    // Every stage drained and finished: the state a restart continues from.  A failed save is said, never hidden.
    if (save_state()) {
      spdlog::info("state saved to {} at shutdown ({} bytes)", state_path, state_counters.bytes.load());
    } else {
      spdlog::error("state NOT saved at shutdown: {} holds the last successful save ({} of {} saves failed)", state_path,
                    state_counters.failures.load(), state_counters.saves.load() + state_counters.failures.load());
      if (rc == kExitOk) rc = kExitState;
    }
  }
  if (recorder) {
    recorder->close();
    spdlog::info("recording closed: {} messages in {}", recorder->written(), recorder->path());
  }
  try {
    publish_status();
  } catch (const std::exception& e) {
    spdlog::error("status: {}", e.what());
  }
  return rc;
}

}  // namespace sextant::runtime
