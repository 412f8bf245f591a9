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

TEST_CASE("the publisher says how far behind real time it publishes: a backlog after a stall shows its lag") {
  config::Channels channels;
  runtime::Publisher publisher(channels, "t", "ekf", [](const std::string&, const std::vector<uint8_t>&, int64_t) {});
  int64_t wall = 1'000'000'000;
  publisher.measure_lag([&wall] { return wall; });
  engine::FusedPose p;
  p.source = "robot";
  p.estimator = "ekf";
  p.covariance = engine::Matrix6::Identity();
  // Live: each pose published 5 ms after its stamp.
  for (int i = 1; i <= 10; ++i) {
    p.utime = wall - 5'000;
    publisher.publish(p);
    wall += 10'000;
  }
  CHECK(publisher.take_lag().max_us == 5'000);
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
  CHECK(publisher.take_lag().max_us == lag.last_us);  // the maximum restarts at each status
}
