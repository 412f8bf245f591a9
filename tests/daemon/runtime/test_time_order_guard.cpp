// The time guard and the rest of the intake's per-sender state: one far-future stamp no longer cuts a body off, a
// true clock jump is followed, per-name state is bounded, and sequence gaps are counted as lost.
#include "daemon/runtime/intake.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <thread>

#include <cstdint>
#include <chrono>
#include <limits>
#include <map>
#include <string>
#include <vector>

using namespace sextant;
using runtime::TimeGuardOptions;
using runtime::TimeOrderGuard;

namespace {

constexpr int64_t kT0 = 1'700'000'000'000'000;  // 2023, in microseconds
constexpr int64_t k2100 = 4'102'444'800'000'000;

// A live run's clocks with the wall clock far in the future (only the per-stream check acts) and the monotonic
// clock at `at` (seconds after an arbitrary origin).
TimeOrderGuard::LiveClock live_at(double at, int64_t wall = std::numeric_limits<int64_t>::max() / 2) {
  static const auto origin = std::chrono::steady_clock::now();
  return {wall,
          origin + std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(at))};
}

runtime::IntakeOptions live_intake() {
  runtime::IntakeOptions o;
  o.live = true;
  return o;
}

template <class Msg>
std::vector<uint8_t> encode(const Msg& m) {
  std::vector<uint8_t> b(static_cast<size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

std::vector<uint8_t> odometry(int64_t utime, const std::string& source, int64_t seq = 0,
                              const std::string& sender = "s") {
  engine::Odometry o;
  o.utime = utime;
  o.source = source;
  o.covariance = engine::Matrix6::Identity();
  return encode(runtime::to_message(o, sender, seq));
}

std::vector<uint8_t> scan(int64_t utime, int32_t sensor) {
  engine::BearingScan s;
  s.utime = utime;
  s.sensor_id = sensor;
  return encode(runtime::to_message(s, "s", 0));
}

}  // namespace

TEST_CASE("one odometry message dated 2100 (or INT64_MAX) is refused and does not move the body's clock") {
  for (int64_t future : {k2100, std::numeric_limits<int64_t>::max()}) {
    runtime::ChannelStats stats;
    runtime::Intake intake(stats, {}, live_intake());
    intake.add_channel("ODOMETRY", runtime::InputKind::kOdometry);
    int accepted = 0;
    for (int k = 0; k < 100; ++k) {
      const auto b = odometry(kT0 + k * 20'000, "robot");
      accepted += intake.accept("ODOMETRY", b.data(), b.size(), runtime::Arrival::now()).has_value() ? 1 : 0;
      if (k == 10) {
        const auto f = odometry(future, "robot");
        CHECK_FALSE(intake.accept("ODOMETRY", f.data(), f.size(), runtime::Arrival::now()).has_value());
      }
    }
    CHECK(accepted == 100);  // before the guard: 11 (every later message "before the previous 4102444800000000")
    const auto c = stats.snapshot().at("ODOMETRY");
    CHECK(c.reasons.at("time_future") == 1);
    CHECK(c.last_error.find("ahead of the wall clock") != std::string::npos);
    CHECK(intake.time_resyncs() == 0);
  }
}

TEST_CASE("live, a stamp far ahead of its stream's clock is refused, unless real time has passed as much") {
  TimeOrderGuard g;  // 60 s of slack
  CHECK_FALSE(g.check("a", kT0, true, 0, live_at(0)));
  CHECK(g.check("a", kT0 + 100'000'000, true, 0, live_at(1))->reason == "time_future");  // 100 s ahead after 1 s
  CHECK(g.check("a", kT0 + 100'000'000, true, 0, live_at(1))->message.find("ahead of the previous") !=
        std::string::npos);
  CHECK_FALSE(g.check("a", kT0 + 100'000'000, true, 0, live_at(50)));  // a sender that paused for 50 s
  // Replay (no live clocks): utime order is the feed's, no far-future check.
  TimeOrderGuard r;
  CHECK_FALSE(r.check("a", kT0, true));
  CHECK_FALSE(r.check("a", k2100, true));
}

TEST_CASE("a clock that truly jumped is followed after the configured number of consistent messages") {
  TimeGuardOptions o;
  o.resync_after = 4;
  TimeOrderGuard g(o);
  const auto at = live_at(0);
  CHECK_FALSE(g.check("a", kT0, true, 0, at));
  CHECK_FALSE(g.check("a", kT0 + 20'000, true, 0, at));
  // Forward: three refused, the fourth accepted and the new clock from then on.
  for (int k = 0; k < 3; ++k) CHECK(g.check("a", k2100 + k * 20'000, true, 0, at)->reason == "time_future");
  CHECK_FALSE(g.check("a", k2100 + 3 * 20'000, true, 0, at));
  CHECK(g.resyncs() == 1);
  CHECK(g.last_resync().find("re-synchronised") != std::string::npos);
  CHECK_FALSE(g.check("a", k2100 + 4 * 20'000, true, 0, at));
  CHECK(g.check("a", kT0 + 40'000, true, 0, at)->reason == "time_order");  // the old clock is now the past
  // Backward (a restarted robot): the same, in replay too.
  for (int k = 1; k < 3; ++k) CHECK(g.check("a", kT0 + k * 1'000'000, true)->reason == "time_order");
  CHECK_FALSE(g.check("a", kT0 + 3 * 1'000'000, true));  // the fourth consistent one (kT0 + 40'000 was the first)
  CHECK(g.resyncs() == 2);
  // Refused messages that disagree with each other never add up to a jump.
  for (int k = 0; k < 20; ++k) CHECK(g.check("a", (k % 2 ? k2100 : 2 * k2100) + k, true, 0, at).has_value());
  CHECK(g.resyncs() == 2);
}

TEST_CASE("live, a stamp far ahead of the wall clock is refused even as a stream's first") {
  TimeOrderGuard g;
  const int64_t wall = kT0;
  CHECK(g.check("a", wall + 61'000'000, true, 0, live_at(0, wall))->reason == "time_future");
  CHECK_FALSE(g.check("a", wall + 59'000'000, true, 0, live_at(0, wall)));
  CHECK(g.streams() == 1);
}

TEST_CASE("a future bearing scan no longer blocks its sensor, landmarks and loops may be late but not far ahead") {
  runtime::ChannelStats stats;
  runtime::Intake intake(stats, {}, live_intake());
  intake.add_channel("BEARINGS", runtime::InputKind::kBearings);
  int accepted = 0;
  for (int k = 0; k < 61; ++k) {
    if (k == 1) {
      const auto f = scan(k2100, 3);
      CHECK_FALSE(intake.accept("BEARINGS", f.data(), f.size(), runtime::Arrival::now()).has_value());
    }
    const auto b = scan(kT0 + k * 100'000, 3);
    accepted += intake.accept("BEARINGS", b.data(), b.size(), runtime::Arrival::now()).has_value() ? 1 : 0;
  }
  CHECK(accepted == 61);

  TimeOrderGuard g;
  const auto at = live_at(0);
  CHECK_FALSE(g.check("LOOP/r", kT0, false, 1, at));
  CHECK_FALSE(g.check("LOOP/r", kT0 - 5'000'000, false, 2, at));        // late: fine
  CHECK(g.check("LOOP/r", kT0, false, 1, at)->reason == "time_order");  // the same loop again
  CHECK_FALSE(g.check("LOOP/r", kT0, false, 3, at));                    // another loop made at the same time
  CHECK(g.check("LOOP/r", k2100, false, 4, at)->reason == "time_future");
}

TEST_CASE("state per name is bounded: new names beyond the cap are refused, idle ones expire") {
  TimeGuardOptions o;
  o.max_streams = 100;
  o.idle_s = 30;
  TimeOrderGuard g(o);
  for (int k = 0; k < 100; ++k) CHECK_FALSE(g.check("body" + std::to_string(k), kT0, true, 0, live_at(0)));
  for (int k = 100; k < 1000; ++k) {
    const auto r = g.check("body" + std::to_string(k), kT0, true, 0, live_at(0));
    REQUIRE(r.has_value());
    CHECK(r->reason == "too_many_sources");
  }
  CHECK(g.streams() == 100);
  CHECK_FALSE(g.check("body5", kT0 + 1, true, 0, live_at(0)));  // a known body is not refused
  // body5 speaks again 15 s in; 40 s in, every other body has been silent for more than 30 s.
  CHECK_FALSE(g.check("body5", kT0 + 2, true, 0, live_at(15)));
  CHECK_FALSE(g.check("newcomer", kT0, true, 0, live_at(40)));
  CHECK(g.expired() == 99);
  CHECK(g.streams() == 2);
  // The names forgotten, for the daemon to free the stages' state of those bodies (Stage::forget), once.
  auto names = g.take_expired();
  CHECK(names.size() == 99);
  CHECK(std::find(names.begin(), names.end(), "body5") == names.end());
  CHECK(std::find(names.begin(), names.end(), "body7") != names.end());
  CHECK(g.take_expired().empty());
}

TEST_CASE("live, a full table makes room from the quietest source silent for evict_idle_s, never in replay") {
  TimeGuardOptions o;
  o.max_streams = 10;
  o.evict_idle_s = 60;  // idle_s stays 0: nothing expires by idling alone
  TimeOrderGuard g(o);
  // Two real robots talk a lot; eight one-off names fill the table.
  for (int k = 0; k < 100; ++k) {
    REQUIRE_FALSE(g.check("robot1", kT0 + k, true, 0, live_at(0)));
    REQUIRE_FALSE(g.check("robot2", kT0 + k, true, 0, live_at(0)));
  }
  for (int k = 0; k < 8; ++k) REQUIRE_FALSE(g.check("flood" + std::to_string(k), kT0, true, 0, live_at(1 + k)));
  // Full, and nobody silent for 60 s yet: refused, known names not slowed.
  CHECK(g.check("newcomer", kT0, true, 0, live_at(30))->reason == "too_many_sources");
  CHECK_FALSE(g.check("robot2", kT0 + 200, true, 0, live_at(30)));
  CHECK(g.evicted() == 0);
  // 62 s in: robot1 (silent since 0) and flood0 (since 1) have been silent for 60 s; flood0 said less: it goes.
  CHECK_FALSE(g.check("newcomer", kT0, true, 0, live_at(62)));
  CHECK(g.evicted() == 1);
  CHECK(g.expired() == 1);
  CHECK(g.take_expired() == std::vector<std::string>{"flood0"});
  CHECK(g.streams() == 10);
  // The next newcomers take flood1.. in their order of silence; robot1, silent longest but with 100 messages, stays
  // while a quieter one can go; robot2 spoke at 30 s and is not silent long enough.
  for (int k = 1; k < 8; ++k) CHECK_FALSE(g.check("late" + std::to_string(k), kT0, true, 0, live_at(70)));
  CHECK(g.evicted() == 8);
  const auto gone = g.take_expired();
  CHECK(std::find(gone.begin(), gone.end(), "robot1") == gone.end());
  CHECK(gone.size() == 7);
  // Now only robot1 is silent long enough among the quiet ones: it gives its place last.
  CHECK_FALSE(g.check("late8", kT0, true, 0, live_at(71)));
  CHECK(g.take_expired() == std::vector<std::string>{"robot1"});
  // Nobody else is silent for 60 s before 90 s (robot2 spoke at 30 s): refused without a scan of the table.
  CHECK(g.check("late9", kT0, true, 0, live_at(72))->reason == "too_many_sources");
  CHECK(g.evicted() == 9);

  // Replay (no live clock) never evicts: its answers must not depend on how fast it runs.
  TimeOrderGuard replay(o);
  for (int k = 0; k < 10; ++k) REQUIRE_FALSE(replay.check("name" + std::to_string(k), kT0, true));
  CHECK(replay.check("one more", kT0, true)->reason == "too_many_sources");
  CHECK(replay.evicted() == 0);
}

TEST_CASE(
    "the intake names the bodies whose odometry stream expired (not sensors, not other channels), by the clock it is "
    "given") {
  runtime::ChannelStats stats;
  runtime::IntakeOptions o;
  o.time.idle_s = 0.05;
  runtime::Intake intake(stats, {}, o);
  intake.add_channel("R/ODOMETRY", runtime::InputKind::kOdometry);
  const auto a = odometry(kT0, "robot/a", 0, "robot/a");
  const auto b = odometry(kT0, "b", 0, "b");
  REQUIRE(intake.accept("R/ODOMETRY", a.data(), a.size(), runtime::Arrival::at_log_time(kT0)));
  REQUIRE(intake.accept("R/ODOMETRY", b.data(), b.size(), runtime::Arrival::at_log_time(kT0)));
  CHECK(intake.take_expired_bodies().empty());
  // 1.1 s later by the given clock (a replay's log time): idle, and past the once-a-second sweep.  No wall time passes.
  const auto c = odometry(kT0 + 1, "b", 1, "b");
  REQUIRE(intake.accept("R/ODOMETRY", c.data(), c.size(), runtime::Arrival::at_log_time(kT0 + 1'100'000)));
  const auto gone = intake.take_expired_bodies();
  REQUIRE(gone.size() == 2);  // both were idle at the sweep (b came back after it)
  CHECK(std::find(gone.begin(), gone.end(), "robot/a") != gone.end());
  CHECK(std::find(gone.begin(), gone.end(), "b") != gone.end());
}

TEST_CASE("a replay's arrival clock keeps the order of every log stamp, a damaged one's saturating without overflow") {
  // The steady clock counts nanoseconds: a microsecond stamp past about 292 years does not fit (a plain conversion
  // would wrap it to a time before the epoch, so that the largest stamp came first).
  constexpr int64_t kMax = std::numeric_limits<int64_t>::max(), kMin = std::numeric_limits<int64_t>::min();
  const std::vector<int64_t> stamps{kMin, kMin / 1000, -k2100, 0, kT0, k2100, kMax / 1000, kMax / 2, kMax};
  for (size_t i = 1; i < stamps.size(); ++i) {
    const runtime::Arrival a = runtime::Arrival::at_log_time(stamps[i - 1]),
                           b = runtime::Arrival::at_log_time(stamps[i]);
    CAPTURE(stamps[i]);
    CHECK(a.steady <= b.steady);
    CHECK(b.wall_utime == stamps[i]);
  }
  // Ordinary stamps are exact, and the extremes leave room for the guard's differences and sums with idle times.
  using std::chrono::microseconds;
  CHECK(runtime::Arrival::at_log_time(kT0).steady.time_since_epoch() == microseconds(kT0));
  CHECK(runtime::Arrival::at_log_time(k2100).steady.time_since_epoch() == microseconds(k2100));
  const auto top = runtime::Arrival::at_log_time(kMax).steady, bottom = runtime::Arrival::at_log_time(kMin).steady;
  CHECK(top - bottom > std::chrono::hours(24 * 365 * 200));
  CHECK(top + std::chrono::hours(24 * 365) > top);
}

TEST_CASE("the intake counts sequence gaps per channel and sender as lost") {
  runtime::ChannelStats stats;
  runtime::Intake intake(stats);
  intake.add_channel("ODOMETRY", runtime::InputKind::kOdometry);
  auto send = [&](int64_t utime, int64_t seq, const std::string& sender) {
    const auto b = odometry(utime, sender, seq, sender);
    intake.accept("ODOMETRY", b.data(), b.size(), runtime::Arrival::now());
  };
  send(kT0 + 1, 0, "a");
  send(kT0 + 2, 1, "a");
  send(kT0 + 3, 5, "a");   // 2, 3, 4 lost
  send(kT0 + 1, 10, "b");  // b's first
  send(kT0 + 2, 12, "b");  // 11 lost
  send(kT0 + 4, 0, "a");   // a restarted: nothing lost
  send(kT0 + 5, 1, "a");
  send(kT0 + 4, 1, "a");  // a repeat (and refused as backwards): nothing lost
  const auto odo = stats.snapshot().at("ODOMETRY");
  CHECK(odo.lost == 4);
  CHECK(odo.lost_by_sender == std::map<std::string, int64_t>{{"a", 3}, {"b", 1}});
}

TEST_CASE("loss by sender is bounded: beyond the first 64 senders that lost messages, one shared entry") {
  runtime::ChannelStats stats;
  for (int k = 0; k < 1000; ++k) stats.lost("ODOMETRY", "sender" + std::to_string(k), 2);
  stats.lost("ODOMETRY", "sender3", 5);    // a named one keeps its own count
  stats.lost("ODOMETRY", "sender999", 1);  // a later one goes on into the shared entry
  const auto c = stats.snapshot().at("ODOMETRY");
  CHECK(c.lost == 2006);
  CHECK(c.lost_by_sender.size() == runtime::ChannelCounts::kMaxLostSenders + 1);
  CHECK(c.lost_by_sender.at("sender3") == 7);
  CHECK(c.lost_by_sender.at(runtime::ChannelCounts::kOtherSenders) == 2 * (1000 - 64) + 1);
  int64_t sum = 0;
  for (const auto& [sender, n] : c.lost_by_sender) sum += n;
  CHECK(sum == c.lost);
}

TEST_CASE(
    "every expired name is told, beyond 4096 at once, and untaken ones are bounded at 2 x max_streams and counted") {
  TimeGuardOptions o;
  o.max_streams = 5000;
  o.idle_s = 30;
  TimeOrderGuard g(o);
  for (int k = 0; k < 5000; ++k) REQUIRE_FALSE(g.check("body" + std::to_string(k), kT0, true, 0, live_at(0)));
  CHECK_FALSE(g.check("newcomer", kT0, true, 0, live_at(40)));
  CHECK(g.expired() == 5000);
  CHECK(g.take_expired().size() == 5000);  // a cap of 4096 used to leave 904 bodies in the stages for good
  CHECK(g.expired_untold() == 0);

  // A caller that never takes them (replay): kept up to 2 x max_streams, the rest counted.
  o.max_streams = 10;
  TimeOrderGuard h(o);
  for (int round = 0; round < 3; ++round) {
    for (int k = 0; k < 10; ++k)
      REQUIRE_FALSE(
          h.check("r" + std::to_string(round) + "b" + std::to_string(k), kT0, true, 0, live_at(100.0 * round)));
    CHECK_FALSE(h.check("tick" + std::to_string(round), kT0, true, 0, live_at(100.0 * round + 50)));
  }
  CHECK(h.expired_untold() > 0);
  CHECK(static_cast<int64_t>(h.take_expired().size()) + h.expired_untold() == h.expired());
}
