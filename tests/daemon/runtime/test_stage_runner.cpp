// Fault injection into a stage thread: an exception from `handle` (a CHOLMOD failure in the smoother) used to reach
// std::terminate.  Now it is counted, kept as the last failure, the stage recovers, and the next events go on.
#include "daemon/runtime/stage_runner.hpp"
#include "daemon/stage_counters.hpp"

#include <doctest/doctest.h>

#include <atomic>
#include <stdexcept>
#include <thread>

using namespace sextant;

using sextant::stage_counters::counter;

namespace {

// Throws on every odometry message whose utime is a multiple of `every`; counts what it handled and recovered.
class FaultyStage final : public engine::Stage {
 public:
  explicit FaultyStage(int64_t every) : every_(every) {}
  engine::StageKind kind() const override { return engine::StageKind::kOther; }
  std::string_view name() const override { return "faulty"; }
  bool accepts(const engine::Event& e) const override { return std::holds_alternative<engine::Odometry>(e); }
  void handle(const engine::Event& e, const engine::Emit& emit) override {
    const auto& o = std::get<engine::Odometry>(e);
    if (o.utime % every_ == 0) throw std::runtime_error("CHOLMOD's update of the factor failed (status -2)");
    ++handled;
    emit(engine::FusedPose{});
  }
  void recover(const engine::Event& e) override {
    recovered_sources.push_back(std::get<engine::Odometry>(e).source);
    if (throw_in_recover) throw std::runtime_error("recovery failed too");
  }
  void finish(const engine::Emit&) override { throw std::logic_error("finish failed"); }
  engine::Counters counters() const override { return {{"handled", handled}}; }
  int64_t handled = 0;
  bool throw_in_recover = false;
  std::vector<std::string> recovered_sources;

 private:
  int64_t every_;
};

runtime::QueuedEvent odometry(int64_t utime) {
  engine::Odometry o;
  o.utime = utime;
  o.source = "body" + std::to_string(utime % 2);
  return {o, std::chrono::steady_clock::now()};
}

}  // namespace

TEST_CASE("a stage that throws is counted, recovers and keeps processing, nothing leaves the thread") {
  FaultyStage stage(10);
  std::atomic<int> emitted{0};
  runtime::StageRunner runner(stage, 256, [&](engine::Output) { ++emitted; });
  runner.start();
  for (int64_t t = 1; t <= 100; ++t) REQUIRE(runner.offer(odometry(t)));
  runner.drain_and_stop();  // finish throws as well
  const auto s = runner.status();
  CHECK(s.processed == 100);
  CHECK(stage.handled == 90);
  CHECK(emitted.load() == 90);
  CHECK(counter(s, "stage_failures") == 11);  // 10 events and finish
  CHECK(counter(s, "stage_recoveries") == 10);
  CHECK(counter(s, "handled") == 90);
  CHECK(stage.recovered_sources == std::vector<std::string>(10, "body0"));
  CHECK(s.last_failure == "finish: finish failed");
}

TEST_CASE("a recovery that throws is a failure too, and the runner still goes on") {
  FaultyStage stage(2);
  stage.throw_in_recover = true;
  runtime::StageRunner runner(stage, 64, [](engine::Output) {});
  runner.start();
  for (int64_t t = 1; t <= 10; ++t) REQUIRE(runner.offer(odometry(t)));
  runner.drain_and_stop();
  const auto s = runner.status();
  CHECK(s.processed == 10);
  CHECK(counter(s, "stage_failures") == 5 + 5 + 1);
  CHECK(counter(s, "stage_recoveries") == 0);
}

namespace {
class SleepyStage final : public engine::Stage {
 public:
  engine::StageKind kind() const override { return engine::StageKind::kOther; }
  std::string_view name() const override { return "sleepy"; }
  bool accepts(const engine::Event&) const override { return true; }
  void handle(const engine::Event&, const engine::Emit&) override {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    ++handled;
  }
  std::atomic<int> handled{0};
};
}  // namespace

TEST_CASE("a bounded drain discards what is left at the deadline and says how much") {
  SleepyStage stage;
  runtime::StageRunner runner(stage, 1000, [](engine::Output) {});
  runner.start();
  for (int64_t t = 1; t <= 200; ++t) REQUIRE(runner.offer(odometry(t)));  // 4 s of work
  const auto t0 = std::chrono::steady_clock::now();
  const int64_t left = runner.drain_and_stop(t0 + std::chrono::milliseconds(200));
  const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  CHECK(took < 2.0);
  CHECK(left > 100);
  CHECK(stage.handled.load() + left == 200);
  CHECK(counter(runner.status(), "drain_discarded") == left);
}

TEST_CASE("status latency covers a recent time window, not a flood long past") {
  runtime::LatencyRecorder r(4096, 10.0);
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < 1000; ++i) r.add(5900, t0);  // a flood: 5.9 s each
  CHECK(r.summary(t0 + std::chrono::seconds(1)).p50_ms == 5900);
  r.add(3, t0 + std::chrono::seconds(20));
  const auto later = r.summary(t0 + std::chrono::seconds(21));
  CHECK(later.samples == 1);
  CHECK(later.p50_ms == 3);
  CHECK(r.summary(t0 + std::chrono::seconds(40)).samples == 0);
}

namespace {
// Counts the bodies it is told to forget.
class ForgettingStage final : public engine::Stage {
 public:
  engine::StageKind kind() const override { return engine::StageKind::kOther; }
  std::string_view name() const override { return "forgetting"; }
  bool accepts(const engine::Event& e) const override { return std::holds_alternative<engine::Odometry>(e); }
  void handle(const engine::Event& e, const engine::Emit&) override {
    ++handled;
    calls.push_back("handle " + std::to_string(engine::event_utime(e)));
  }
  void forget(const std::string& source) override {
    forgotten.push_back(source);
    calls.push_back("forget " + source);
  }
  int64_t handled = 0;
  std::vector<std::string> forgotten, calls;
};
}  // namespace

TEST_CASE("a stage runner forgets a body in order with the events before, and keeps the orders a full queue refuses") {
  {
    ForgettingStage stage;
    runtime::StageRunner runner(stage, 16, [](engine::Output) {});
    REQUIRE(runner.offer(odometry(1)));
    runner.forget("a");
    REQUIRE(runner.offer(odometry(2)));
    runner.start();
    runner.drain_and_stop();
    CHECK(stage.calls == std::vector<std::string>{"handle 1", "forget a", "handle 2"});
    CHECK_FALSE(sextant::stage_counters::has_counter(runner.status().counters, "forget_out_of_order"));  // none
  }
  ForgettingStage stage;
  runtime::StageRunner runner(stage, 16, [](engine::Output) {});
  std::vector<std::string> told;
  runner.on_forget([&](const std::string& s) { told.push_back(s); });
  REQUIRE(runner.offer(odometry(1)));
  for (int k = 0; k < 5000; ++k) runner.forget("body" + std::to_string(k));
  runner.start();
  runner.drain_and_stop();
  CHECK(stage.forgotten.size() == 5000);  // a cap of 4096 used to drop the rest silently
  CHECK(told.size() == 5000);
  CHECK(stage.handled == 1);
  CHECK(counter(runner.status(), "forget_out_of_order") == 5000 - 15);  // the queue held the event and 15 orders
  // A message that re-synchronised its body's clock: the body is forgotten just before it, and counted.
  ForgettingStage second;
  runtime::StageRunner resync(second, 16, [](engine::Output) {});
  auto first = odometry(3);
  first.forget_first = "body1";
  REQUIRE(resync.offer(odometry(1)));
  REQUIRE(resync.offer(first));
  resync.start();
  resync.drain_and_stop();
  CHECK(second.forgotten == std::vector<std::string>{"body1"});
  CHECK(second.handled == 2);
  CHECK(counter(resync.status(), "resync_forgets") == 1);
}
