// The inertial keyframe smoother stage: a body at rest with wheel odometry and GNSS stays under its antenna, published
// as "inertial_graph" at the configured rate with a finite positive semi-definite covariance, its tilt observable and
// its yaw not (nothing moves); a smoother restarted by a sample of absurd rates is counted; a sensor without a
// mounting is counted; the engine makes the stage only when asked; a
// body driving on a heading it does not know finds it from its first fixes and then follows them.
#include "daemon/engine/engine.hpp"
#include "daemon/stage_counters.hpp"
#include "daemon/engine/inertial_graph_stage.hpp"
#include "daemon/engine/straight_drive.hpp"

#include <doctest/doctest.h>

#include <Eigen/Eigenvalues>

#include <numbers>

using namespace sextant;
using namespace sextant::engine;

using sextant::stage_counters::counter;

namespace {

constexpr int64_t kT0 = 1'700'000'000'000'000;

InertialConfig config() {
  InertialConfig c;
  c.enabled = true;
  c.graph.enabled = true;
  c.mountings.push_back({"", "imu", {0, 0, 0}, {0, 0, 0}});
  c.mountings.push_back({"", "gps", {0, 0, 1}, {0, 0, 0}});
  c.publish_rate_hz = 10;
  return c;
}

ImuSample at_rest(int64_t utime, const std::string& frame = "imu") {
  ImuSample s;
  s.utime = utime;
  s.source = "robot";
  s.frame = frame;
  s.angular_velocity = Eigen::Vector3d::Zero();
  s.linear_acceleration = Eigen::Vector3d(0, 0, 9.80665);
  return s;
}

Odometry still(int64_t utime) {
  Odometry o;
  o.utime = utime;
  o.source = "robot";
  o.planar = true;
  o.increment_covariance = Matrix6::Identity() * 1e-8;
  o.twist = Odometry::Twist{};
  return o;
}

}  // namespace

TEST_CASE("inertial graph stage: a body at rest stays under its antenna, tilt observable, yaw not") {
  InertialConfig c = config();
  c.gnss_heading.align = GnssHeadingConfig::Align::kNever;  // at rest: the start's yaw is taken as ENU
  InertialGraphStage stage(c);
  std::vector<FusedPose> out;
  std::vector<GeoPose> geo;
  const Emit emit = [&](Output o) {
    if (const auto* f = std::get_if<FusedPose>(&o)) out.push_back(*f);
    if (const auto* g = std::get_if<GeoPose>(&o)) geo.push_back(*g);
  };
  GnssFix fix;
  fix.source = "robot";
  fix.frame = "gps";
  fix.latitude = 47.0, fix.longitude = 8.0, fix.altitude = 500;
  fix.position_covariance = Eigen::Matrix3d::Identity() * 0.25;
  for (int k = 0; k <= 20 * 200; ++k) {  // 20 s: IMU 200 Hz, odometry 50 Hz, GNSS 5 Hz
    const int64_t t = kT0 + 5'000 * k;
    stage.handle(at_rest(t), emit);
    if (k % 4 == 0) stage.handle(still(t), emit);
    if (k % 40 == 0) {
      fix.utime = t;
      stage.handle(fix, emit);  // the datum is the first fix: the antenna (1 m up) at the origin
    }
  }
  REQUIRE(!out.empty());
  const FusedPose& last = out.back();
  CHECK(last.estimator == "inertial_graph");
  CHECK(out.size() >= 195);  // 10 Hz over 20 s
  CHECK((last.pose.position - Eigen::Vector3d(0, 0, -1)).norm() < 0.05);
  CHECK(last.covariance.allFinite());
  CHECK(Eigen::SelfAdjointEigenSolver<Matrix6>(last.covariance).eigenvalues().minCoeff() >= -1e-12);
  CHECK(counter(stage, "started") == 1);
  CHECK(counter(stage, "gnss_anchored") == 1);
  CHECK(counter(stage, "keyframes") >= 38);
  CHECK(counter(stage, "failed_solves") == 0);
  CHECK(counter(stage, "restarts") == 0);
  CHECK(counter(stage, "tilt_observable") == 1);
  CHECK(counter(stage, "yaw_observable") == 0);
  // Its poses on the Earth too: 1 m under the antenna at the datum, as "inertial_graph".
  REQUIRE(!geo.empty());
  CHECK(geo.back().estimator == "inertial_graph");
  CHECK(geo.back().utime == last.utime);
  CHECK(std::abs(geo.back().latitude - 47.0) * 111'000 < 0.05);
  CHECK(geo.back().altitude == doctest::Approx(499).epsilon(1e-4));
}

TEST_CASE(
    "inertial graph stage: a smoother restarted by a sample of absurd rates is counted on the status, and goes on") {
  InertialConfig c = config();
  c.gnss_heading.align = GnssHeadingConfig::Align::kNever;
  InertialGraphStage stage(c);
  FusedPose last;
  const Emit emit = [&](Output o) {
    if (const auto* f = std::get_if<FusedPose>(&o)) last = *f;
  };
  for (int k = 0; k <= 10 * 200; ++k) {  // 10 s at rest, IMU 200 Hz and odometry 50 Hz; one wild sample at 3 s
    const int64_t t = kT0 + 5'000 * k;
    ImuSample s = at_rest(t);
    if (k == 600)
      s.angular_velocity = Eigen::Vector3d::Constant(1e300), s.linear_acceleration = Eigen::Vector3d::Constant(-1e308);
    stage.handle(s, emit);
    if (k % 4 == 0) stage.handle(still(t), emit);
  }
  CHECK(counter(stage, "restarts") == 1);
  CHECK(last.utime >= kT0 + 9'900'000);  // published to the end
  CHECK(last.pose.position.allFinite());
  CHECK(last.pose.position.norm() < 0.05);
  CHECK(last.covariance.allFinite());
}

TEST_CASE("inertial graph stage: a sample from a frame without a mounting is counted, the engine makes it on request") {
  InertialGraphStage stage(config());
  int published = 0;
  const Emit emit = [&](Output) { ++published; };
  stage.handle(at_rest(kT0, "unknown_frame"), emit);
  CHECK(published == 0);
  CHECK(counter(stage, "unmounted") == 1);

  EngineConfig c;
  c.inertial = config();
  auto has_it = [](const std::vector<std::unique_ptr<Stage>>& stages) {
    for (const auto& s : stages)
      if (s->kind() == StageKind::kInertialGraph) return true;
    return false;
  };
  CHECK(has_it(make_stages(c, nullptr)));
  c.inertial.graph.enabled = false;
  CHECK_FALSE(has_it(make_stages(c, nullptr)));
}

TEST_CASE("inertial graph stage: an unknown heading (160 degrees) is found from the first fixes, then followed") {
  const test::StraightDrive d(160 * std::numbers::pi / 180, 60);
  InertialGraphStage stage(config());
  FusedPose last;
  const Emit emit = [&](Output o) {
    if (const auto* f = std::get_if<FusedPose>(&o)) last = *f;
  };
  for (const Event& e : d.events) stage.handle(e, emit);
  CHECK(counter(stage, "gnss_heading_aligned") == 1);
  CHECK(counter(stage, "gnss_heading_waiting") == 0);
  CHECK(counter(stage, "failed_solves") == 0);
  const double t_end = static_cast<double>(last.utime - test::StraightDrive::kT0) * 1e-6;
  CHECK((last.pose.position - d.body_enu(t_end)).head<2>().norm() < 1.0);
  const Eigen::Vector3d x = last.pose.orientation * Eigen::Vector3d::UnitX();
  CHECK(std::abs(std::remainder(std::atan2(x.y(), x.x()) - d.heading, 2 * std::numbers::pi)) < 0.03);
}
