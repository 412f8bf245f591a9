// The inertial filter stage: a body at rest stays put with a finite, positive semi-definite covariance, published at
// the configured rate; a sensor without a mounting is refused and counted; a GNSS fix far from the estimate is gated.
#include "daemon/engine/inertial_stage.hpp"

#include <doctest/doctest.h>

#include <Eigen/Eigenvalues>

using namespace sextant;
using namespace sextant::engine;

namespace {

constexpr int64_t kT0 = 1'700'000'000'000'000;

InertialConfig config() {
  InertialConfig c;
  c.enabled = true;
  c.mountings.push_back({"", "imu", {0, 0, 0}, {0, 0, 0}});
  c.mountings.push_back({"", "gps", {0, 0, 1}, {0, 0, 0}});
  c.publish_rate_hz = 50;
  return c;
}

ImuSample at_rest(int64_t utime, const std::string& frame = "imu") {
  ImuSample s;
  s.utime = utime;
  s.source = "robot";
  s.frame = frame;
  s.angular_velocity = Eigen::Vector3d::Zero();
  s.linear_acceleration = Eigen::Vector3d(0, 0, 9.80665);  // level, at rest: the specific force points up
  return s;
}

int64_t counter(const Stage& s, const std::string& name) {
  for (const auto& [n, v] : s.counters())
    if (n == name) return v;
  return -1;
}

}  // namespace

TEST_CASE("inertial stage: a level IMU at rest keeps the body at rest, published at the configured rate") {
  InertialStage stage(config());
  std::vector<FusedPose> out;
  const Emit emit = [&](Output o) { out.push_back(std::get<FusedPose>(o)); };
  for (int k = 0; k <= 1000; ++k) stage.handle(at_rest(kT0 + 5'000 * k), emit);  // 200 Hz for 5 s
  CHECK(out.size() == 251);                                                      // 50 Hz over 5 s, and the first sample
  const FusedPose& last = out.back();
  CHECK(last.estimator == "inertial");
  CHECK(last.pose.position.norm() < 1e-6);
  CHECK(last.pose.orientation.angularDistance(Eigen::Quaterniond::Identity()) < 1e-6);
  CHECK(last.covariance.allFinite());
  CHECK(Eigen::SelfAdjointEigenSolver<Matrix6>(last.covariance).eigenvalues().minCoeff() >= -1e-12);
  CHECK(last.covariance(0, 0) > out.front().covariance(0, 0));  // dead reckoning on an IMU grows
}

TEST_CASE("inertial stage: a sample from a frame without a mounting is refused and counted") {
  InertialStage stage(config());
  int published = 0;
  const Emit emit = [&](Output) { ++published; };
  stage.handle(at_rest(kT0, "unknown_frame"), emit);
  CHECK(published == 0);
  CHECK(counter(stage, "unmounted") == 1);
  CHECK(counter(stage, "started") == 0);
}

TEST_CASE("inertial stage: GNSS fixes at the datum hold the body, a fix 200 m off is gated, not fused") {
  InertialStage stage(config());
  std::vector<FusedPose> out;
  const Emit emit = [&](Output o) { out.push_back(std::get<FusedPose>(o)); };
  GnssFix fix;
  fix.source = "robot";
  fix.frame = "gps";
  fix.latitude = 47.0;
  fix.longitude = 8.0;
  fix.altitude = 500;
  fix.position_covariance = Eigen::Matrix3d::Identity() * 0.25;
  for (int k = 0; k <= 2000; ++k) {
    stage.handle(at_rest(kT0 + 5'000 * k), emit);
    if (k % 40 == 0) {
      fix.utime = kT0 + 5'000 * k;
      stage.handle(fix, emit);  // the datum is the first fix: the antenna (1 m up) at the origin
    }
  }
  CHECK(counter(stage, "updates_gated") == 0);
  const double before = out.back().pose.position.norm();
  CHECK(before < 1.1);  // the body 1 m under its antenna
  GnssFix outlier = fix;
  outlier.utime = kT0 + 5'000 * 2001;
  outlier.latitude += 200.0 / 111'000;  // 200 m north
  stage.handle(outlier, emit);
  stage.handle(at_rest(kT0 + 5'000 * 2002), emit);
  CHECK(counter(stage, "updates_gated") == 1);
  CHECK((out.back().pose.position.norm() - before) < 0.01);
}
