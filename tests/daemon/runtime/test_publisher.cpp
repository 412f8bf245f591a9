// The publisher's last FusedPose time per estimator channel and source (its monotonic check): forgotten with the body
// by one estimator only, and bounded (the one published longest ago in data time goes first, counted).
#include "daemon/runtime/publisher.hpp"

#include <doctest/doctest.h>

using namespace sextant;

TEST_CASE("the publisher's last FusedPose times are forgotten with their body and bounded") {
  config::Channels channels;
  int64_t sent = 0;
  runtime::Publisher publisher(
      channels, "t", "ekf", [&](const std::string&, const std::vector<uint8_t>&, int64_t) { ++sent; },
      /*max_tracked=*/4);
  auto pose = [](const std::string& estimator, const std::string& source, int64_t utime) {
    engine::FusedPose p;
    p.estimator = estimator;
    p.source = source;
    p.utime = utime;
    return p;
  };
  publisher.publish(pose("ekf", "a", 100));
  publisher.publish(pose("ekf", "a", 50));  // not after the last one
  CHECK(publisher.not_monotonic() == 1);
  publisher.publish(pose("dead_reckoning", "a", 10));
  CHECK(publisher.fused_pose_sources() == 2);
  // Forgotten by one estimator only: that channel takes the body's new clock, the other still refuses it.
  publisher.forget("ekf", "a");
  CHECK(publisher.fused_pose_sources() == 1);
  CHECK(publisher.fused_pose_sources_forgotten() == 1);
  publisher.publish(pose("ekf", "a", 50));
  publisher.publish(pose("dead_reckoning", "a", 5));
  CHECK(publisher.not_monotonic() == 2);
  // 100 names: at most 4 kept, the one published longest ago in data time goes first.
  for (int i = 0; i < 100; ++i) publisher.publish(pose("ekf", "n" + std::to_string(i), 1000 + i));
  CHECK(publisher.fused_pose_sources() == 4);
  CHECK(publisher.fused_pose_sources_evicted() == 98);
  publisher.publish(pose("ekf", "n99", 2000));  // kept: still checked
  publisher.publish(pose("ekf", "n99", 1999));
  CHECK(publisher.not_monotonic() == 3);
  CHECK(sent == 3 + 100 + 1);
}

namespace {

/// A publisher whose wall clock is `wall` (microseconds, set by the test), and a pose of body "robot" from the EKF.
struct LagClock {
  runtime::Publisher publisher;
  int64_t wall;
  engine::FusedPose p;
  explicit LagClock(int64_t start)
      : publisher(config::Channels{}, "t", "ekf", [](const std::string&, const std::vector<uint8_t>&, int64_t) {}),
        wall(start) {
    publisher.measure_lag([this] { return wall; });
    p.source = "robot";
    p.estimator = "ekf";
    p.covariance = engine::Matrix6::Identity();
  }
  LagClock(const LagClock&) = delete;
  LagClock& operator=(const LagClock&) = delete;
};

}  // namespace

TEST_CASE("the publisher says how far behind real time it publishes: a backlog after a stall shows its lag") {
  LagClock clock(1'000'000'000);
  auto& [publisher, wall, p] = clock;
  // Live: each pose published 5 ms after its stamp.
  for (int i = 1; i <= 10; ++i) {
    p.utime = wall - 5'000;
    publisher.publish(p);
    wall += 10'000;
  }
  const auto live = publisher.take_lag();
  CHECK(live.max_us == 5'000);
  CHECK(live.usual_us == 5'000);
  CHECK(live.excess_us() == 0);
  // Stopped for 20 s: the backlog (stamped during the stall) is published late, and says so.
  const int64_t stalled_from = wall;
  wall += 20'000'000;
  for (int i = 0; i < 5; ++i) {
    p.utime = stalled_from + i * 10'000;
    publisher.publish(p);
  }
  const auto lag = publisher.take_lag();
  CHECK(lag.max_us == 20'000'000);
  CHECK(lag.last_us == 20'000'000 - 40'000);
  CHECK(lag.usual_us == 5'000);  // the stall is beyond the usual lag
  CHECK(lag.excess_us() == 20'000'000 - 5'000);
  CHECK(publisher.take_lag().max_us == lag.last_us);  // the maximum restarts at each status
}

TEST_CASE("the publisher's usual lag: a sender's clock offset is not a stall, a stall beyond it is") {
  LagClock clock(1'800'000'000'000'000);
  auto& [publisher, wall, p] = clock;
  const int64_t offset = 3LL * 365 * 86'400 * 1'000'000;  // a log played live with its stamps of three years ago
  int64_t stamp = wall - offset;
  const auto publish_for = [&](double seconds, int64_t delay_us) {
    for (int i = 0; i < static_cast<int>(seconds * 100); ++i) {
      p.utime = stamp;
      wall += delay_us;
      publisher.publish(p);
      wall += 10'000 - delay_us;
      stamp += 10'000;
    }
  };
  for (int report = 0; report < 5; ++report) {  // status every second, poses 2-4 ms late on the sender's clock
    publish_for(1.0, 2'000 + 500 * report);
    const auto lag = publisher.take_lag();
    CHECK(lag.max_us > offset);
    CHECK(lag.usual_us == offset + 2'000);
    CHECK(lag.excess_us() < 10'000);
    CHECK_FALSE(lag.falling_behind(1'000'000));
  }
  // A 5 s stall: the backlog is published 5 s later than usual.
  wall += 5'000'000;
  publish_for(1.0, 0);
  const auto stalled = publisher.take_lag();
  CHECK(stalled.excess_us() >= 5'000'000 - 2'000);
  CHECK(stalled.usual_us == offset + 2'000);
  CHECK(stalled.falling_behind(1'000'000));
  // The usual lag follows a clock that was set: the daemon's stepped 10 s ahead reads as late for kUsualLagReports
  // reports, then as the usual lag.
  stamp = wall - offset;  // the backlog drained
  wall += 10'000'000;
  for (size_t report = 0; report < runtime::Publisher::kUsualLagReports; ++report) {
    publish_for(0.05, 2'000);
    const auto lag = publisher.take_lag();
    if (report < runtime::Publisher::kUsualLagReports - 6) CHECK(lag.excess_us() >= 9'990'000);  // 6 older reports
  }
  publish_for(0.05, 2'000);
  const auto followed = publisher.take_lag();
  CHECK(followed.usual_us == offset + 10'000'000 + 2'000);
  CHECK(followed.excess_us() == 0);
}

TEST_CASE("the publisher's lag: falling behind is a lag that grows, not one that falls back") {
  LagClock clock(1'800'000'000'000'000);
  auto& [publisher, wall, p] = clock;
  int64_t stamp = wall - 3'600'000'000;  // a log of an hour ago
  // One report per wall second, poses every 10 ms of data time, played at `rate` times real time.
  const auto report_at = [&](double rate) {
    const auto wall_step = static_cast<int64_t>(10'000 / rate);
    for (int64_t t = 0; t < 1'000'000; t += wall_step) {
      p.utime = stamp;
      publisher.publish(p);
      stamp += 10'000;
      wall += wall_step;
    }
    return publisher.take_lag();
  };
  // Played 2.5x faster than real time: the lag falls by 1.5 s a second; far from the usual within each second,
  // yet never behind.
  for (int report = 0; report < 10; ++report) {
    const auto lag = report_at(2.5);
    if (report > 0) CHECK(lag.excess_us() > 1'400'000);
    CHECK_FALSE(lag.falling_behind(1'000'000));
  }
  // Played at 0.5x (the daemon or its input half as fast as the data): the lag grows by 0.5 s a second; behind
  // once it stands a second over the usual, and from then on at every report.
  int behind = 0;
  for (int report = 0; report < 10; ++report) {
    const auto lag = report_at(0.5);
    CHECK(lag.falling_behind(1'000'000) == (lag.excess_us() > 1'000'000));
    behind += lag.falling_behind(1'000'000) ? 1 : 0;
  }
  CHECK(behind >= 7);
  // Back to real time at the lag reached: it no longer grows, so no longer behind, though still over the usual.
  for (int report = 0; report < 5; ++report) {
    const auto lag = report_at(1.0);
    CHECK(lag.excess_us() > 4'000'000);
    CHECK_FALSE(lag.falling_behind(1'000'000));
  }
}
