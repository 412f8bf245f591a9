#include "daemon/runtime/daemon.hpp"

#include "daemon/engine/engine.hpp"
#include "daemon/runtime/engine_driver.hpp"
#include "daemon/runtime/raw_subscription.hpp"
#include "daemon/runtime/recorder.hpp"
#include "daemon/runtime/shared_graph_corrections.hpp"
#include "daemon/runtime/state_directory.hpp"
#include "daemon/runtime/status_report.hpp"
#include "daemon/runtime/udp_drops.hpp"

#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>

#include <chrono>
#include <functional>
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

// Everything sextantd runs between start-up and shutdown, as named steps: the engine (restored from the state
// directory), the driver around it with one thread per stage, the LCM thread that records and routes, the status
// and state threads, and the bounded shutdown.
class Daemon {
 public:
  Daemon(const config::DaemonConfig& cfg, lcm::LCM& lcm) : cfg_(cfg), lcm_(lcm), log_(cfg.log_rate_limit_s) {}

  // The steps of a run, in order; each returns an ExitCode other than kExitOk to stop there.
  int restore_engine();
  int open_recorder();
  void start_driver();
  void subscribe();
  void start_periodic_threads();
  int handle_until(const std::atomic<bool>& stop);
  /// kExitOk, or kExitState when the last state save failed (it is never reported as saved).
  int shut_down();
  /// The LCM thread's handler of every message (raw_subscription.hpp).
  void on_message(const lcm_recv_buf_t& rbuf, const std::string& channel);

 private:
  bool save_state();
  void publish_status();
  engine::Counters runtime_counters() const;
  void every(double period_s, const std::function<void()>& f);

  const config::DaemonConfig& cfg_;
  lcm::LCM& lcm_;
  RateLimitedLog log_;
  std::unique_ptr<engine::Engine> engine_;
  std::unique_ptr<EngineDriver> driver_;
  std::unique_ptr<Recorder> recorder_;
  std::string state_path_;
  // The intake's own counters, copied out by the LCM thread for the status thread (the intake is not thread-safe).
  std::atomic<int64_t> resyncs_{0}, sources_{0}, expired_{0}, evicted_{0};
  std::atomic<int64_t> state_saves_{0}, state_failures_{0}, state_bytes_{0}, state_save_us_{0};
  std::atomic<bool> intake_stopped_{false};
  std::thread status_thread_, state_thread_;
  Clock::time_point started_ = Clock::now();
  int64_t drops_at_start_ = udp_receive_drops().value_or(0);
  std::unique_ptr<StatusReport> report_;
};

// The state directory: the stages continue from the saved state (state_directory.hpp).  A bad file stops start-up,
// or with --discard-bad-state is set aside and the engine starts fresh.
int Daemon::restore_engine() {
  // The graph stage and the graph pose stage run on two threads: their correction board is guarded.
  engine_ = std::make_unique<engine::Engine>(cfg_.engine, std::make_shared<SharedGraphCorrections>());
  if (cfg_.state_dir.empty()) return kExitOk;
  state_path_ = state_file_path(cfg_.state_dir);
  std::error_code ec;
  std::filesystem::create_directories(cfg_.state_dir, ec);
  if (ec) {
    spdlog::error("--state-dir {}: cannot create it: {}", cfg_.state_dir, ec.message());
    return kExitState;
  }
  std::vector<engine::Stage*> stages;
  for (auto& s : engine_->stages()) stages.push_back(s.get());
  try {
    if (restore_stages(state_path_, cfg_.engine_fingerprint, stages))
      spdlog::info("state restored from {}", state_path_);
    else
      spdlog::info("no state in {}: starting fresh; state is saved there every {} s", cfg_.state_dir,
                   cfg_.state_period_s);
    return kExitOk;
  } catch (const StateFileError& e) {
    if (!cfg_.discard_bad_state) {
      spdlog::error(
          "bad state file: {}\n  Move it away, or start with --discard-bad-state to set it aside and start "
          "fresh.",
          e.what());
      return kExitState;
    }
    try {
      const std::string aside = set_state_file_aside(state_path_);
      spdlog::warn("bad state file: {}; set aside as {} (--discard-bad-state): starting fresh", e.what(), aside);
    } catch (const StateFileError& e2) {
      spdlog::error("{}", e2.what());
      return kExitState;
    }
  }
  // The stages may have been partly restored.
  engine_ = std::make_unique<engine::Engine>(cfg_.engine, std::make_shared<SharedGraphCorrections>());
  return kExitOk;
}

int Daemon::open_recorder() {
  if (cfg_.record.empty()) return kExitOk;
  try {
    recorder_ = std::make_unique<Recorder>(cfg_.record, 65536);
  } catch (const std::exception& e) {
    spdlog::error("--record: {}", e.what());
    return kExitRuntime;
  }
  if (recorder_->path() != cfg_.record)
    spdlog::warn("--record: {} exists and is kept; recording to {}", cfg_.record, recorder_->path());
  return kExitOk;
}

void Daemon::start_driver() {
  DriverOptions o;
  o.live = true;
  o.lanes = StageLanes::kStageThreads;
  o.on_reject = [this](const std::string& c, const std::string& r, const std::string& m) { log_.warn(c, r, m); };
  driver_ = std::make_unique<EngineDriver>(
      cfg_, *engine_,
      [this](const std::string& channel, const std::vector<uint8_t>& bytes, int64_t) {
        lcm_.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
      },
      std::move(o));
  report_ = std::make_unique<StatusReport>(cfg_.name);
  driver_->publisher().measure_lag([] {
    return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
        .count();
  });
  driver_->start();
}

// The LCM thread: every message on the bus is recorded (when asked) and, on an input channel, given to the driver.
// Nothing a message does may end the LCM thread: what escapes is counted as an "internal" rejection.
void Daemon::on_message(const lcm_recv_buf_t& rbuf, const std::string& channel) {
  try {
    if (recorder_ != nullptr) {
      const auto* b = static_cast<const uint8_t*>(rbuf.data);
      recorder_->record(LogRecord{rbuf.recv_utime, channel, std::vector<uint8_t>(b, b + rbuf.data_size)});
    }
    driver_->input(channel, rbuf.data, rbuf.data_size, Arrival::now());
    const Intake& intake = driver_->intake();
    if (intake.time_resyncs() != resyncs_.load()) {
      resyncs_ = intake.time_resyncs();
      spdlog::warn("{} (time_resyncs: {}; every stage forgets the body)", intake.last_resync(), intake.time_resyncs());
    }
    sources_ = static_cast<int64_t>(intake.sources());
    expired_ = intake.sources_expired();
    evicted_ = intake.sources_evicted();
  } catch (const std::exception& e) {
    driver_->stats().rejected(channel, "internal", channel + ": " + e.what());
  }
}

void Daemon::subscribe() {
  // LCM keeps 30 undelivered messages per subscription by default and silently drops beyond that; our own bounded
  // queues do the counting, so give LCM's queue room for bursts.
  lcm_subscription_set_queue_capacity(subscribe_raw(lcm_, ".*", this), cfg_.queue_capacity * 8);
  const std::string primary = engine_->primary_estimator();
  spdlog::info("sextantd '{}' running on {}; stages: {}; primary estimator: {}", cfg_.name,
               cfg_.lcm_url.empty() ? "the default LCM URL" : cfg_.lcm_url, driver_->runners().size(),
               primary.empty() ? "none" : primary);
}

bool Daemon::save_state() {
  try {
    const StateSave s = save_stages(state_path_, cfg_.engine_fingerprint, driver_->runners());
    if (state_saves_.fetch_add(1) == 0)
      spdlog::info("state saved to {}: {} bytes, {:.1f} ms from the stages, {:.1f} ms to write", state_path_, s.bytes,
                   s.collect_ms, s.write_ms);
    state_bytes_ = static_cast<int64_t>(s.bytes);
    state_save_us_ = static_cast<int64_t>(1000 * (s.collect_ms + s.write_ms));
    return true;
  } catch (const std::exception& e) {
    const int64_t n = ++state_failures_;
    if (n <= 10 || (n & (n - 1)) == 0) spdlog::error("state not saved ({} failure(s) so far): {}", n, e.what());
    return false;
  }
}

engine::Counters Daemon::runtime_counters() const {
  const Publisher& p = driver_->publisher();
  engine::Counters c{{"fused_pose_not_monotonic", p.not_monotonic()},
                     {"fused_pose_sources", static_cast<int64_t>(p.fused_pose_sources())},
                     {"fused_pose_sources_forgotten", p.fused_pose_sources_forgotten()},
                     {"fused_pose_sources_evicted", p.fused_pose_sources_evicted()},
                     {"time_resyncs", resyncs_.load()},
                     {"sources", sources_.load()},
                     {"sources_expired", expired_.load()},
                     {"sources_evicted", evicted_.load()}};
  if (const auto drops = udp_receive_drops()) c.push_back({"udp_receive_drops", *drops - drops_at_start_});
  const Publisher::Lag lag = driver_->publisher().take_lag();
  c.push_back({"publish_lag_us", lag.last_us});
  c.push_back({"publish_lag_us_max", lag.max_us});
  c.push_back({"publish_lag_usual_us", lag.usual_us});
  if (lag.falling_behind(1'000'000))
    spdlog::warn(
        "published up to {:.1f} s later than usual since the last status (a stall, or a backlog; the usual "
        "lag, {:.3f} s, includes the senders' clock offset)",
        lag.excess_us() * 1e-6, lag.usual_us * 1e-6);
  if (!state_path_.empty()) {
    c.push_back({"state_saves", state_saves_.load()});
    c.push_back({"state_save_failures", state_failures_.load()});
    c.push_back({"state_bytes", state_bytes_.load()});
    c.push_back({"state_save_us", state_save_us_.load()});
  }
  if (recorder_) {
    c.push_back({"recorded", recorder_->written()});
    c.push_back({"record_dropped", recorder_->dropped()});
    c.push_back({"record_failed", recorder_->failed() ? 1 : 0});
  }
  return c;
}

void Daemon::publish_status() {
  try {
    Publisher& p = driver_->publisher();
    p.publish(report_->build(std::chrono::duration<double>(Clock::now() - started_).count(),
                             driver_->stats().snapshot(), driver_->stage_status(), runtime_counters(), p.counts(),
                             p.bytes()));
  } catch (const std::exception& e) {
    spdlog::error("status: {}", e.what());
  }
}

// Calls `f` every `period_s` until intake stops (checked every 20 ms).
void Daemon::every(double period_s, const std::function<void()>& f) {
  auto next = Clock::now();
  const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(period_s));
  while (!intake_stopped_.load()) {
    next += period;
    while (!intake_stopped_.load() && Clock::now() < next) std::this_thread::sleep_for(std::chrono::milliseconds(20));
    if (!intake_stopped_.load()) f();
  }
}

// SEXTANT_STATUS on a thread of its own; periodic saves on another (each stage saved between two of its events).
void Daemon::start_periodic_threads() {
  status_thread_ = std::thread([this] { every(cfg_.status_period_s, [this] { publish_status(); }); });
  if (!state_path_.empty())
    state_thread_ = std::thread([this] { every(cfg_.state_period_s, [this] { save_state(); }); });
}

int Daemon::handle_until(const std::atomic<bool>& stop) {
  auto next_tick = Clock::now();
  while (!stop.load()) {
    // A signal interrupts the poll (EINTR) and makes handleTimeout return -1: that is a shutdown, not a failure.
    if (lcm_.handleTimeout(100) < 0 && !stop.load()) {
      spdlog::error("LCM handle failed; stopping. {}", bus_failure_help(cfg_.lcm_url));
      return kExitBus;
    }
    if (Clock::now() >= next_tick) {  // the fleet exchange's clock between messages (on this, input()'s, thread)
      driver_->tick(Arrival::now());
      next_tick = Clock::now() + std::chrono::milliseconds(200);
    }
  }
  return kExitOk;
}

// Intake stops, the queues drain within drain_timeout_s (a stage still at work then is interrupted: it ends after
// its current step, StageRunner::drain_and_stop), the stages finish; then the last state save, the recording
// flushed and closed, and a last status.
int Daemon::shut_down() {
  intake_stopped_ = true;
  spdlog::info("shutting down: draining {} stage queue(s) (at most {} s)", driver_->runners().size(),
               cfg_.drain_timeout_s);
  const auto begun = Clock::now();
  const auto deadline =
      begun + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(cfg_.drain_timeout_s));
  if (const int64_t left = driver_->finish(deadline); left > 0)
    spdlog::warn("{} queued event(s) discarded at the drain timeout ({} s)", left, cfg_.drain_timeout_s);
  spdlog::info("stages drained and finished in {:.3f} s", std::chrono::duration<double>(Clock::now() - begun).count());
  status_thread_.join();
  if (state_thread_.joinable()) state_thread_.join();
  int rc = kExitOk;
  if (!state_path_.empty()) {
    // Every stage drained and finished: the state a restart continues from.  A failed save is said, never hidden.
    if (save_state()) {
      spdlog::info("state saved to {} at shutdown ({} bytes)", state_path_, state_bytes_.load());
    } else {
      spdlog::error("state NOT saved at shutdown: {} holds the last successful save ({} of {} saves failed)",
                    state_path_, state_failures_.load(), state_saves_.load() + state_failures_.load());
      rc = kExitState;
    }
  }
  if (recorder_) {
    recorder_->close();
    spdlog::info("recording closed: {} messages in {}", recorder_->written(), recorder_->path());
  }
  publish_status();
  return rc;
}

}  // namespace

int run_daemon(const config::DaemonConfig& cfg, const std::atomic<bool>& stop) {
  lcm::LCM lcm(cfg.lcm_url);
  if (!lcm.good()) {
    spdlog::error("{}", bus_failure_help(cfg.lcm_url));
    return kExitBus;
  }
  Daemon daemon(cfg, lcm);
  if (const int rc = daemon.restore_engine(); rc != kExitOk) return rc;
  if (const int rc = daemon.open_recorder(); rc != kExitOk) return rc;
  daemon.start_driver();
  daemon.subscribe();
  daemon.start_periodic_threads();
  const int rc = daemon.handle_until(stop);
  const int shutdown_rc = daemon.shut_down();
  return rc != kExitOk ? rc : shutdown_rc;
}

}  // namespace sextant::runtime
