// The one engine driver (daemon/runtime/engine_driver.hpp): the daemon's lanes (a thread per stage) and replay's
// (inline) give the same outputs for the same messages and clock, a body's clock resync and an idle expiry included;
// and when a body's clock truly jumps, every stage and the publisher forget the body in order with its earlier
// messages, so that its later messages are processed and published again instead of refused as out of order.
#include "daemon/engine/engine.hpp"
#include "daemon/stage_counters.hpp"
#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/engine_driver.hpp"
#include "daemon/runtime/publisher.hpp"
#include "daemon/runtime/shared_graph_corrections.hpp"

#include <doctest/doctest.h>

#include <chrono>
#include <map>
#include <mutex>

using namespace sextant;

using sextant::stage_counters::counter;

namespace {

std::vector<uint8_t> odometry_bytes(int64_t utime, const std::string& source, int i, int64_t seq) {
  engine::Odometry o;
  o.utime = utime;
  o.source = source;
  o.planar = true;
  o.pose.position = Eigen::Vector3d(0.5 * i, 0, 0);
  o.covariance = engine::Matrix6::Identity() * 1e-3 * (i + 1);
  engine::Matrix6 q = engine::Matrix6::Identity() * 1e-4;
  o.increment_covariance = q;
  auto m = runtime::to_message(o, "robot", seq);
  std::vector<uint8_t> b(static_cast<size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

}  // namespace

TEST_CASE(
    "a body whose clock jumps back is re-synchronised, forgotten by every stage and the publisher, and published "
    "again") {
  config::DaemonConfig cfg;
  cfg.time_resync_messages = 3;
  auto engine = std::make_unique<engine::Engine>(cfg.engine, std::make_shared<runtime::SharedGraphCorrections>());
  std::mutex mutex;
  std::map<std::string, std::vector<int64_t>> published;  // FUSED_POSE* channel -> utimes
  runtime::DriverOptions options;
  options.live = true;
  options.lanes = runtime::StageLanes::kStageThreads;
  runtime::EngineDriver driver(
      cfg, *engine,
      [&](const std::string& channel, const std::vector<uint8_t>&, int64_t utime) {
        std::lock_guard lock(mutex);
        if (channel.rfind("FUSED_POSE", 0) == 0) published[channel].push_back(utime);
      },
      options);
  const std::string channel = cfg.channels.full(cfg.channels.odometry);
  driver.start();

  const int64_t now =
      std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
          .count();
  const int64_t before_jump = now - 10'000'000, after_jump = now - 3'600'000'000LL;  // a restart an hour back
  int64_t seq = 0;
  auto send = [&](int64_t utime, int i) {
    const auto b = odometry_bytes(utime, "robot", i, seq++);
    return driver.input(channel, b.data(), b.size(), runtime::Arrival::now());
  };
  const runtime::Intake& intake = driver.intake();
  for (int i = 0; i < 20; ++i) CHECK(send(before_jump + 100'000 * i, i));
  // The robot restarted with a clock an hour back: the first two messages are refused, the third re-synchronises.
  CHECK_FALSE(send(after_jump, 0));
  CHECK_FALSE(send(after_jump + 100'000, 1));
  CHECK(intake.time_resyncs() == 0);
  CHECK(send(after_jump + 200'000, 2));
  CHECK(intake.time_resyncs() == 1);
  CHECK(intake.resynced_body() == "robot");
  for (int i = 3; i < 20; ++i) CHECK(send(after_jump + 100'000 * i, i));
  CHECK(intake.resynced_body().empty());
  driver.finish();

  CHECK(driver.publisher().not_monotonic() == 0);
  CHECK(driver.publisher().fused_pose_sources_forgotten() >= 1);
  int channels = 0;
  for (const auto& [name, utimes] : published) {
    const std::string& ch = name;  // INFO captures it in a lambda: not a structured binding (clang 14)
    int old_clock = 0, new_clock = 0;
    for (int64_t u : utimes) (u >= before_jump ? old_clock : new_clock) += 1;
    INFO(ch << ": " << old_clock << " before the jump, " << new_clock << " after");
    if (old_clock == 0) continue;
    ++channels;
    CHECK(new_clock > 0);
    CHECK(utimes.back() >= after_jump + 100'000 * 19 - 1'000'000);  // still published at the end of the run
  }
  CHECK(channels >= 3);  // dead reckoning, the EKF and the graph's fused pose
  const auto status = driver.stage_status();
  for (size_t i = 0; i < status.size(); ++i) {
    INFO(status[i].name);
    if (engine->stages()[i]->accepts(engine::Event{engine::Odometry{}})) {
      CHECK(counter(status[i], "resync_forgets") == 1);
      if (sextant::stage_counters::has_counter(status[i].counters, "odometry_out_of_order"))  // the graph's
        CHECK(counter(status[i], "odometry_out_of_order") == 0);
    }
  }
}

namespace {

struct Sent {
  std::string channel;
  std::vector<uint8_t> bytes;
  int64_t utime;
};

// Two bodies at 10 Hz for 30 s of data time: "a" restarts with a clock 100 s back at 10 s, "b" is silent from 12 s to
// 20 s (longer than source_idle_s) and comes back.
std::vector<Sent> resync_and_idle_run(const config::DaemonConfig& cfg) {
  const std::string channel = cfg.channels.full(cfg.channels.odometry);
  const int64_t t0 = 1'700'000'000'000'000;
  std::vector<Sent> run;
  int64_t seq_a = 0, seq_b = 0;
  for (int k = 0; k < 300; ++k) {
    const int64_t t = t0 + 100'000 * k;
    const int64_t ta = k < 100 ? t : t - 100'000'000;  // a's clock jumps back 100 s at k = 100
    run.push_back({channel, odometry_bytes(ta, "a", k, seq_a++), t});
    if (k < 120 || k >= 200) run.push_back({channel, odometry_bytes(t + 50'000, "b", k, seq_b++), t + 50'000});
  }
  return run;
}

// Every message of the run through a driver with the given lanes, the log's time as the clock; the published bytes
// per channel.
std::map<std::string, std::vector<std::vector<uint8_t>>> drive(const config::DaemonConfig& cfg,
                                                               runtime::StageLanes lanes, int64_t* forgotten,
                                                               int64_t* resyncs) {
  auto engine = std::make_unique<engine::Engine>(cfg.engine, std::make_shared<runtime::SharedGraphCorrections>());
  std::mutex mutex;
  std::map<std::string, std::vector<std::vector<uint8_t>>> out;
  runtime::DriverOptions options;
  options.lanes = lanes;
  options.zero_solve_time = true;
  runtime::EngineDriver driver(
      cfg, *engine,
      [&](const std::string& channel, const std::vector<uint8_t>& bytes, int64_t) {
        std::lock_guard lock(mutex);
        out[channel].push_back(bytes);
      },
      options);
  driver.start();
  for (const Sent& m : resync_and_idle_run(cfg))
    driver.input(m.channel, m.bytes.data(), m.bytes.size(), runtime::Arrival::at_log_time(m.utime));
  driver.finish();
  *forgotten = driver.intake().sources_expired();
  *resyncs = driver.intake().time_resyncs();
  return out;
}

}  // namespace

TEST_CASE(
    "the daemon's lanes and replay's give the same outputs for the same messages, a resync and an idle expiry "
    "included") {
  config::DaemonConfig cfg;
  cfg.time_resync_messages = 3;
  cfg.source_idle_s = 5;             // b's 8 s of silence expires it (by the log's time)
  cfg.engine.graph.enabled = false;  // its fused pose follows the graph thread's timing, not the data alone
  cfg.engine.association.enabled = false;
  int64_t forgotten_inline = 0, forgotten_threads = 0, resyncs_inline = 0, resyncs_threads = 0;
  const auto inline_out = drive(cfg, runtime::StageLanes::kInline, &forgotten_inline, &resyncs_inline);
  const auto thread_out = drive(cfg, runtime::StageLanes::kStageThreads, &forgotten_threads, &resyncs_threads);
  CHECK(resyncs_inline == 1);
  CHECK(forgotten_inline >= 1);  // b's odometry stream (and a's old clock's, when idle long enough)
  CHECK(resyncs_threads == resyncs_inline);
  CHECK(forgotten_threads == forgotten_inline);
  REQUIRE(inline_out.size() >= 2);
  CHECK(inline_out.size() == thread_out.size());
  for (const auto& [channel, messages] : inline_out) {
    const std::string ch = channel;
    INFO(ch);
    REQUIRE(thread_out.contains(ch));
    const auto& other = thread_out.at(ch);
    CHECK(messages.size() == other.size());
    size_t first_difference = 0;
    while (first_difference < std::min(messages.size(), other.size()) &&
           messages[first_difference] == other[first_difference])
      ++first_difference;
    INFO("first difference at message " << first_difference << " of " << messages.size());
    CHECK(first_difference == messages.size());
  }
  // b was forgotten and published again after its silence; a after its clock jumped back.
  const auto& fused = inline_out.at(cfg.channels.full(cfg.channels.fused_pose));
  CHECK(fused.size() >= 2 * 300 - 80 - 10);
}

TEST_CASE(
    "replay's pipelined lanes publish what its inline lanes publish, in the same order, a resync and an idle expiry "
    "included") {
  config::DaemonConfig cfg;
  cfg.time_resync_messages = 3;
  cfg.source_idle_s = 5;  // b's 8 s of silence expires it: every stage and the publisher forget it, in order
  // The graph and its fused pose run on the second thread; dead reckoning and the EKF on the caller's.
  struct Run {
    std::vector<std::pair<std::string, std::vector<uint8_t>>> published;  // in publish order
    std::vector<size_t> handled;                                          // stage indices, in on_handled order
    std::vector<int64_t> processed;
    int64_t forgotten = 0, resyncs = 0, publisher_forgot = 0;
  };
  const auto drive_lanes = [&](runtime::StageLanes lanes) {
    auto engine = std::make_unique<engine::Engine>(cfg.engine, std::make_shared<runtime::SharedGraphCorrections>());
    Run run;
    runtime::DriverOptions options;
    options.lanes = lanes;
    options.zero_solve_time = true;
    options.on_handled = [&](size_t stage, double) { run.handled.push_back(stage); };
    runtime::EngineDriver driver(
        cfg, *engine,
        [&](const std::string& channel, const std::vector<uint8_t>& bytes, int64_t) {
          run.published.emplace_back(channel, bytes);
        },
        options);
    for (const Sent& m : resync_and_idle_run(cfg))
      driver.input(m.channel, m.bytes.data(), m.bytes.size(), runtime::Arrival::at_log_time(m.utime));
    driver.finish();
    for (const auto& s : driver.stage_status()) run.processed.push_back(s.processed);
    run.forgotten = driver.intake().sources_expired();
    run.resyncs = driver.intake().time_resyncs();
    run.publisher_forgot = driver.publisher().fused_pose_sources_forgotten();
    return run;
  };
  const Run one = drive_lanes(runtime::StageLanes::kInline);
  const Run two = drive_lanes(runtime::StageLanes::kPipelined);
  CHECK(one.resyncs == 1);
  CHECK(one.forgotten >= 1);
  CHECK(one.publisher_forgot >= 2);  // b expired, a re-synchronised: per estimator that publishes them
  CHECK(two.resyncs == one.resyncs);
  CHECK(two.forgotten == one.forgotten);
  CHECK(two.publisher_forgot == one.publisher_forgot);
  CHECK(two.processed == one.processed);
  CHECK(two.handled == one.handled);
  REQUIRE(one.published.size() > 1000);
  REQUIRE(two.published.size() == one.published.size());
  size_t first_difference = 0;
  while (first_difference < one.published.size() && one.published[first_difference] == two.published[first_difference])
    ++first_difference;
  INFO("first difference at message " << first_difference << " of " << one.published.size());
  CHECK(first_difference == one.published.size());
}
