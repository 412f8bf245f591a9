// The publisher's last FusedPose time per estimator channel and source (its monotonic check): forgotten with the body
// by one estimator only, and bounded (the one published longest ago in data time goes first, counted).
#include "daemon/runtime/publisher.hpp"

#include <doctest/doctest.h>

using namespace sextant;

TEST_CASE("the publisher's last FusedPose times are forgotten with their body and bounded") {
  config::Channels channels;
  int64_t sent = 0;
  runtime::Publisher publisher(channels, "t", "ekf", [&](const std::string&, const std::vector<uint8_t>&, int64_t) { ++sent; },
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
