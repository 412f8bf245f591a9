// The daemon's input path (intake -> stage threads -> publisher) when a body's clock truly jumps: the intake
// re-synchronises its stream, and every stage and the publisher forget the body in order with its earlier messages,
// so that its later messages are processed and published again instead of refused as out of order.
#include "daemon/engine/engine.hpp"
#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/input_router.hpp"
#include "daemon/runtime/publisher.hpp"
#include "daemon/runtime/shared_graph_corrections.hpp"

#include <doctest/doctest.h>

#include <chrono>
#include <map>
#include <mutex>

using namespace sextant;

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

int64_t counter(const runtime::StageStatus& s, const std::string& name) {
  for (const auto& [n, v] : s.counters)
    if (n == name) return v;
  return -1;
}

}  // namespace

TEST_CASE("a body whose clock jumps back is re-synchronised, forgotten by every stage and the publisher, and published again") {
  config::DaemonConfig cfg;
  cfg.time_resync_messages = 3;
  auto engine = std::make_unique<engine::Engine>(cfg.engine, std::make_shared<runtime::SharedGraphCorrections>());
  std::mutex mutex;
  std::map<std::string, std::vector<int64_t>> published;  // FUSED_POSE* channel -> utimes
  runtime::Publisher publisher(cfg.channels, cfg.name, engine->primary_estimator(),
                               [&](const std::string& channel, const std::vector<uint8_t>&, int64_t utime) {
                                 std::lock_guard lock(mutex);
                                 if (channel.rfind("FUSED_POSE", 0) == 0) published[channel].push_back(utime);
                               });
  const engine::Emit emit = [&publisher](engine::Output o) { publisher.publish(o); };
  std::vector<std::unique_ptr<runtime::StageRunner>> runners;
  for (auto& stage : engine->stages()) {
    runners.push_back(std::make_unique<runtime::StageRunner>(*stage, 1024, emit));
    if (const std::string estimator(stage->estimator()); !estimator.empty())
      runners.back()->on_forget([&publisher, estimator](const std::string& s) { publisher.forget(estimator, s); });
  }
  runtime::ChannelStats stats;
  runtime::Intake intake(stats, {}, runtime::intake_options(cfg, /*live=*/true));
  const std::string channel = cfg.channels.full(cfg.channels.odometry);
  intake.add_channel(channel, runtime::InputKind::kOdometry);
  for (auto& r : runners) r->start();

  const int64_t now = std::chrono::duration_cast<std::chrono::microseconds>(
                          std::chrono::system_clock::now().time_since_epoch()).count();
  const int64_t before_jump = now - 10'000'000, after_jump = now - 3'600'000'000LL;  // a restart an hour back
  int64_t seq = 0;
  auto send = [&](int64_t utime, int i) {
    const auto b = odometry_bytes(utime, "robot", i, seq++);
    return runtime::route_input(intake, runners, stats, channel, b.data(), b.size(), std::chrono::steady_clock::now());
  };
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
  for (auto& r : runners) r->drain_and_stop();

  CHECK(publisher.not_monotonic() == 0);
  CHECK(publisher.fused_pose_sources_forgotten() >= 1);
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
  CHECK(channels >= 2);  // at least dead reckoning and the EKF
  for (size_t i = 0; i < runners.size(); ++i) {
    const auto status = runners[i]->status();
    INFO(status.name);
    if (engine->stages()[i]->accepts(engine::Event{engine::Odometry{}})) {
      CHECK(counter(status, "resync_forgets") == 1);
      CHECK(counter(status, "odometry_out_of_order") <= 0);  // the graph's (-1: a stage without it)
      CHECK(counter(status, "out_of_order") <= 0);           // the graph pose stage's
    }
  }
}
