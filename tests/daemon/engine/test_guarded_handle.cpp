// handle_guarded: what a stage throws never escapes, the stage is asked to recover, and the next event is handled.
#include "daemon/engine/guarded_handle.hpp"

#include <doctest/doctest.h>

#include <stdexcept>

namespace {
using namespace sextant::engine;

// Throws on odometry from "bad"; its recover() throws `recover_throws` times, then resets `broken`.
struct FlakyStage final : Stage {
  int handled = 0, recovered = 0, recover_throws = 0;
  bool broken = false;
  StageKind kind() const override { return StageKind::kOther; }
  std::string_view name() const override { return "flaky"; }
  bool accepts(const Event&) const override { return true; }
  void handle(const Event& e, const Emit&) override {
    if (broken) throw std::logic_error("still broken");
    if (const auto* o = std::get_if<Odometry>(&e); o && o->source == "bad") {
      broken = true;
      throw std::runtime_error("CHOLMOD said no");
    }
    ++handled;
  }
  void recover(const Event&) override {
    if (recover_throws > 0) {
      --recover_throws;
      throw 42;  // not a std::exception
    }
    broken = false;
    ++recovered;
  }
};

Event odometry(const std::string& source) {
  Odometry o;
  o.source = source;
  return o;
}
}  // namespace

TEST_CASE("handle_guarded: a throwing handle is reported, the stage recovers, the next event is handled") {
  FlakyStage stage;
  const Emit emit = [](Output) {};
  CHECK_FALSE(handle_guarded(stage, odometry("good"), emit).has_value());
  auto failure = handle_guarded(stage, odometry("bad"), emit);
  REQUIRE(failure.has_value());
  CHECK(failure->message == "handle: CHOLMOD said no");
  CHECK(failure->recovered);
  CHECK(failure->recover_message.empty());
  CHECK_FALSE(handle_guarded(stage, odometry("good"), emit).has_value());
  CHECK(stage.handled == 2);
  CHECK(stage.recovered == 1);
}

TEST_CASE("handle_guarded: a recover that throws is reported too, and nothing escapes") {
  FlakyStage stage;
  stage.recover_throws = 1;
  const Emit emit = [](Output) {};
  auto failure = handle_guarded(stage, odometry("bad"), emit);
  REQUIRE(failure.has_value());
  CHECK_FALSE(failure->recovered);
  CHECK(failure->recover_message == "recover: an exception that is not a std::exception");
  // Still broken: the next event fails too, and this time recover works.
  failure = handle_guarded(stage, odometry("good"), emit);
  REQUIRE(failure.has_value());
  CHECK(failure->message == "handle: still broken");
  CHECK(failure->recovered);
  CHECK_FALSE(handle_guarded(stage, odometry("good"), emit).has_value());
  CHECK(stage.handled == 1);
}
