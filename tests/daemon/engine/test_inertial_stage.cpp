// The inertial filter stage: a body at rest stays put with a finite, positive semi-definite covariance, published at
// the configured rate; a sensor without a mounting is refused and counted; a GNSS fix far from the estimate is gated;
// a body driving on a heading it does not know finds it from its first fixes and then follows them, where trusting
// its start yaw has the gate refuse them.
#include "daemon/engine/inertial_stage.hpp"
#include "daemon/stage_counters.hpp"
#include "daemon/engine/straight_drive.hpp"

#include <doctest/doctest.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <numbers>

using namespace sextant;
using namespace sextant::engine;

using sextant::stage_counters::counter;

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

}  // namespace

TEST_CASE("inertial stage: a level IMU at rest keeps the body at rest, published at the configured rate") {
  InertialStage stage(config());
  std::vector<FusedPose> out;
  const Emit emit = [&](Output o) {
    if (const auto* f = std::get_if<FusedPose>(&o)) out.push_back(*f);
  };
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
  InertialConfig c = config();
  c.gnss_heading.align = GnssHeadingConfig::Align::kNever;  // at rest: the start's yaw is taken as ENU
  InertialStage stage(c);
  std::vector<FusedPose> out;
  std::vector<GeoPose> geo;
  const Emit emit = [&](Output o) {
    if (const auto* f = std::get_if<FusedPose>(&o)) out.push_back(*f);
    if (const auto* g = std::get_if<GeoPose>(&o)) geo.push_back(*g);
  };
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
  // From the first fix on, every pose also on the Earth, at the pose's time: 1 m under the antenna at (47, 8, 500).
  REQUIRE(!geo.empty());
  CHECK(geo.back().utime == out.back().utime);
  CHECK(static_cast<size_t>(std::count_if(
            out.begin(), out.end(), [&](const FusedPose& f) { return f.utime >= geo.front().utime; })) == geo.size());
  CHECK(geo.back().heading_known);
  CHECK(std::abs(geo.back().latitude - 47.0) * 111'000 < 0.1);
  CHECK(std::abs(geo.back().longitude - 8.0) * 111'000 * std::cos(47.0 * std::numbers::pi / 180) < 0.1);
  CHECK(geo.back().altitude == doctest::Approx(499).epsilon(1e-4));
  CHECK(geo.back().datum == Eigen::Vector3d(47.0, 8.0, 500));
  GnssFix outlier = fix;
  outlier.utime = kT0 + 5'000 * 2001;
  outlier.latitude += 200.0 / 111'000;  // 200 m north
  stage.handle(outlier, emit);
  stage.handle(at_rest(kT0 + 5'000 * 2002), emit);
  CHECK(counter(stage, "updates_gated") == 1);
  CHECK((out.back().pose.position.norm() - before) < 0.01);
}

namespace {

struct DriveResult {
  FusedPose last;
  int64_t gated, aligned, waiting, reacquired;
  GeoPose last_geo;
  int geo_heading_unknown = 0, geo_heading_known = 0;  // GeoPoses published before and after the heading was known
};

DriveResult drive(const test::StraightDrive& d, GnssHeadingConfig::Align align) {
  InertialConfig c = config();
  c.gnss_heading.align = align;
  InertialStage stage(c);
  DriveResult r;
  const Emit emit = [&](Output o) {
    if (const auto* f = std::get_if<FusedPose>(&o)) r.last = *f;
    if (const auto* g = std::get_if<GeoPose>(&o)) {
      r.last_geo = *g;
      ++(g->heading_known ? r.geo_heading_known : r.geo_heading_unknown);
    }
  };
  for (const Event& e : d.events) stage.handle(e, emit);
  r.gated = counter(stage, "updates_gated");
  r.aligned = counter(stage, "gnss_heading_aligned");
  r.waiting = counter(stage, "gnss_heading_waiting");
  r.reacquired = counter(stage, "gnss_heading_reacquired");
  return r;
}

double yaw_of(const Eigen::Quaterniond& q) {
  const Eigen::Vector3d x = q * Eigen::Vector3d::UnitX();
  return std::atan2(x.y(), x.x());
}

}  // namespace

TEST_CASE("inertial stage: an unknown heading (160, -170, 90 degrees) is found from the first fixes, then followed") {
  for (double deg : {160.0, -170.0, 90.0}) {
    CAPTURE(deg);
    const test::StraightDrive d(deg * std::numbers::pi / 180, 60);
    const DriveResult r = drive(d, GnssHeadingConfig::Align::kAuto);
    const double t_end = static_cast<double>(r.last.utime - test::StraightDrive::kT0) * 1e-6;
    CHECK(r.aligned == 1);
    CHECK(r.waiting == 0);
    CHECK(r.gated <= 2);
    // On the Earth from the first fix, saying that the heading is not known until it is.
    CHECK(r.geo_heading_unknown > 0);
    CHECK(r.geo_heading_known > 0);
    CHECK(r.last_geo.heading_known);
    CHECK(r.last_geo.utime == r.last.utime);
    const Eigen::Vector3d e = r.last.pose.position - d.body_enu(t_end);
    CHECK(e.head<2>().norm() < 1.0);  // after 116 m
    CHECK(std::abs(std::remainder(yaw_of(r.last.pose.orientation) - d.heading, 2 * std::numbers::pi)) < 0.03);
    // The published covariance is over the body-frame perturbation: the error seen from the body.
    const Eigen::Vector3d e_body = r.last.pose.orientation.conjugate() * e;
    const Eigen::Matrix3d P = r.last.covariance.topLeftCorner<3, 3>();
    const double var = e_body.dot(P.inverse() * e_body);
    CHECK(var < 16.3);  // chi-square(3) 99.9 %: the covariance covers the error
  }
  // Trusting the start's yaw (0, the unit has none): the fixes disagree with the track and the gate refuses them.
  const test::StraightDrive d(160 * std::numbers::pi / 180, 60);
  const DriveResult r = drive(d, GnssHeadingConfig::Align::kNever);
  CHECK(r.aligned == 0);
  CHECK(r.gated > 200);  // of 300 fixes
  CHECK((r.last.pose.position - d.body_enu(60)).head<2>().norm() > 50);
}

TEST_CASE("inertial stage: fixes that jump 15 m for good are gated, then the heading and position are found anew") {
  const test::StraightDrive d(160 * std::numbers::pi / 180, 60, 30);
  const DriveResult r = drive(d, GnssHeadingConfig::Align::kAuto);
  CHECK(r.reacquired == 1);
  CHECK(r.gated == 10);  // reacquire_after
  CHECK(r.aligned == 2);
  CHECK(r.waiting == 0);
  const double t_end = static_cast<double>(r.last.utime - test::StraightDrive::kT0) * 1e-6;
  const Eigen::Vector3d jumped = d.body_enu(t_end) + Eigen::Vector3d(15, 0, 0);
  CHECK((r.last.pose.position - jumped).head<2>().norm() < 1.0);
  CHECK(std::abs(std::remainder(yaw_of(r.last.pose.orientation) - d.heading, 2 * std::numbers::pi)) < 0.03);
}
