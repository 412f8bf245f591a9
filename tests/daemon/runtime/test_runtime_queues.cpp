// Bounded queues, intake time-order rules, and the stage runner under overload.
#include "daemon/runtime/bounded_queue.hpp"
#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/intake.hpp"
#include "daemon/runtime/latency_recorder.hpp"
#include "daemon/runtime/stage_runner.hpp"

#include <doctest/doctest.h>

#include <atomic>
#include <thread>

using namespace sextant;

TEST_CASE("a full queue refuses and counts, keeps order, and drains after close") {
  runtime::BoundedQueue<int> q(3);
  CHECK(q.try_push(1));
  CHECK(q.try_push(2));
  CHECK(q.try_push(3));
  CHECK_FALSE(q.try_push(4));
  CHECK(q.dropped() == 1);
  CHECK(q.size() == 3);
  q.close();
  CHECK_FALSE(q.try_push(5));
  CHECK(*q.pop() == 1);
  CHECK(*q.pop() == 2);
  CHECK(*q.pop() == 3);
  CHECK_FALSE(q.pop().has_value());
}

TEST_CASE("many producers against a slow consumer: memory bounded, every item accounted for") {
  runtime::BoundedQueue<int> q(64);
  std::atomic<int> consumed{0};
  std::thread consumer([&] {
    while (auto v = q.pop()) {
      ++consumed;
      std::this_thread::sleep_for(std::chrono::microseconds(20));
    }
  });
  std::vector<std::thread> producers;
  std::atomic<int> accepted{0};
  for (int p = 0; p < 4; ++p)
    producers.emplace_back([&] {
      for (int i = 0; i < 5000; ++i)
        if (q.try_push(i)) ++accepted;
    });
  for (auto& t : producers) t.join();
  CHECK(q.high_water() <= 64);
  q.close();
  consumer.join();
  CHECK(consumed.load() == accepted.load());
  CHECK(static_cast<int>(q.dropped()) + accepted.load() == 20000);
  CHECK(q.dropped() > 0);
}

TEST_CASE("latency percentiles by nearest rank") {
  runtime::LatencyRecorder r(100);
  for (int i = 1; i <= 100; ++i) r.add(i);
  const auto s = r.summary();
  CHECK(s.p50_ms == 50);  // 50 of the 100 samples are at or below 50
  CHECK(s.p99_ms == 99);
  CHECK(s.max_ms == 100);
  for (int i = 0; i < 100; ++i) r.add(1000);  // the window slides
  CHECK(r.summary().p50_ms == 1000);
}

namespace {
std::vector<uint8_t> odometry_bytes(int64_t utime, const std::string& source) {
  engine::Odometry o;
  o.utime = utime;
  o.source = source;
  o.covariance = engine::Matrix6::Identity();
  auto m = runtime::to_message(o, "t", 0);
  std::vector<uint8_t> b(static_cast<size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}
}  // namespace

TEST_CASE("intake rejects duplicate and backwards odometry per source, counts per channel") {
  runtime::ChannelStats stats;
  std::vector<std::string> reasons;
  runtime::Intake intake(stats,
                         [&](const std::string&, const std::string& r, const std::string&) { reasons.push_back(r); });
  intake.add_channel("ODOMETRY", runtime::InputKind::kOdometry);
  auto a = odometry_bytes(100, "a");
  auto b = odometry_bytes(100, "b");
  auto a_dup = odometry_bytes(100, "a");
  auto a_back = odometry_bytes(50, "a");
  auto a_next = odometry_bytes(200, "a");
  CHECK(intake.accept("ODOMETRY", a.data(), a.size(), runtime::Arrival::now()).has_value());
  CHECK(intake.accept("ODOMETRY", b.data(), b.size(), runtime::Arrival::now())
            .has_value());  // another source may share the time
  CHECK_FALSE(intake.accept("ODOMETRY", a_dup.data(), a_dup.size(), runtime::Arrival::now()).has_value());
  CHECK_FALSE(intake.accept("ODOMETRY", a_back.data(), a_back.size(), runtime::Arrival::now()).has_value());
  CHECK(intake.accept("ODOMETRY", a_next.data(), a_next.size(), runtime::Arrival::now()).has_value());
  const uint8_t junk[] = {0xde, 0xad, 0xbe, 0xef, 0, 0, 0, 0, 1};
  CHECK_FALSE(intake.accept("ODOMETRY", junk, sizeof junk, runtime::Arrival::now()).has_value());
  CHECK_FALSE(intake.accept("OTHER", a.data(), a.size(), runtime::Arrival::now())
                  .has_value());  // not an input channel: ignored, not counted
  const auto snap = stats.snapshot();
  const auto& c = snap.at("ODOMETRY");
  CHECK(c.received == 6);
  CHECK(c.decoded == 3);
  CHECK(c.rejected == 3);
  CHECK(c.reasons.at("time_order") == 2);
  CHECK(c.reasons.at("fingerprint") == 1);
  CHECK(snap.count("OTHER") == 0);
  CHECK(reasons == std::vector<std::string>{"time_order", "time_order", "fingerprint"});
}

namespace {
// A stage that is slow on purpose, to overload its queue.
class SlowStage final : public engine::Stage {
 public:
  engine::StageKind kind() const override { return engine::StageKind::kOther; }
  std::string_view name() const override { return "slow"; }
  bool accepts(const engine::Event& e) const override { return std::holds_alternative<engine::Odometry>(e); }
  void handle(const engine::Event&, const engine::Emit& emit) override {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
    ++handled;
    emit(engine::FusedPose{});
  }
  void finish(const engine::Emit&) override { finished = true; }
  engine::Counters counters() const override { return {{"handled", handled}}; }
  int64_t handled = 0;
  bool finished = false;
};
}  // namespace

TEST_CASE("a stage runner under a flood drops beyond its queue, drains on stop and calls finish") {
  SlowStage stage;
  std::atomic<int> emitted{0};
  runtime::StageRunner runner(stage, 16, [&](engine::Output) { ++emitted; });
  runner.start();
  int refused = 0;
  for (int i = 0; i < 500; ++i) {
    runtime::QueuedEvent e{engine::Odometry{}, std::chrono::steady_clock::now()};
    if (!runner.offer(e)) ++refused;
  }
  CHECK(refused > 0);
  CHECK(runner.status().queue_depth <= 16);
  runner.drain_and_stop();
  const auto s = runner.status();
  CHECK(stage.finished);
  CHECK(s.processed + s.dropped == 500);
  CHECK(s.dropped == refused);
  CHECK(emitted.load() == s.processed);
  CHECK(s.counters.at(0).second == s.processed);
  CHECK(s.latency.max_ms >= 2.0);
}
