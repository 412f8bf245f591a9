// imu_t and gnss_t at the intake: what a sensor sends arrives as an event with its groups, and every bad field is
// refused with its name (the wire layout is checked against lcm-gen's encoder in test_wire_layout.cpp's way here).
#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/encode_message.hpp"
#include "daemon/runtime/wire_layout.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <limits>

using namespace sextant;

namespace {

sextant::imu_t imu() {
  sextant::imu_t m{};
  m.utime = 1'700'000'000'000'000;
  m.sender = "test";
  m.source = "husky";
  m.frame = "imu_link";
  m.has_angular_velocity = true;
  m.angular_velocity[2] = 0.1;
  m.angular_velocity_covariance[0] = m.angular_velocity_covariance[4] = m.angular_velocity_covariance[8] = 1e-4;
  m.has_linear_acceleration = true;
  m.linear_acceleration[2] = 9.81;
  m.has_orientation = true;
  m.orientation_has_yaw = true;
  m.orientation[0] = 1;
  return m;
}

sextant::gnss_t gnss() {
  sextant::gnss_t m{};
  m.utime = 1'700'000'000'000'000;
  m.sender = "test";
  m.source = "husky";
  m.frame = "gps_link";
  m.status = sextant::gnss_t::STATUS_FIX;
  m.latitude = 40.0;
  m.longitude = -83.0;
  m.altitude = 200;
  m.position_covariance[0] = m.position_covariance[4] = m.position_covariance[8] = 4;
  return m;
}

template <class Msg>
runtime::Decoded decode(runtime::InputKind kind, const Msg& m) {
  const auto b = encode(m);
  return runtime::decode_event(kind, b.data(), b.size());
}

std::string rejection(const runtime::Decoded& d) {
  const auto* r = std::get_if<runtime::Rejection>(&d);
  return r ? r->reason + ": " + r->message : std::string("accepted");
}

}  // namespace

TEST_CASE("an IMU sample decodes with the groups it carries, and its layout is lcm-gen's") {
  auto m = imu();
  m.has_orientation = false;  // a unit without an orientation estimate
  const auto b = encode(m);
  CHECK_FALSE(runtime::wire_error(runtime::wire_layout<sextant::imu_t>(), b.data(), b.size()));
  for (size_t cut = 8; cut < b.size(); cut += 7)
    CHECK(runtime::wire_error(runtime::wire_layout<sextant::imu_t>(), b.data(), cut));
  const auto d = runtime::decode_event(runtime::InputKind::kImu, b.data(), b.size());
  REQUIRE(std::holds_alternative<engine::Event>(d));
  const auto& e = std::get<engine::ImuSample>(std::get<engine::Event>(d));
  CHECK(e.source == "husky");
  CHECK(e.frame == "imu_link");
  REQUIRE(e.angular_velocity);
  CHECK((*e.angular_velocity)[2] == 0.1);
  REQUIRE(e.linear_acceleration);
  CHECK(e.linear_acceleration_covariance.isZero());  // not stated
  CHECK_FALSE(e.orientation);
}

TEST_CASE("bad IMU samples are refused naming the field") {
  auto none = imu();
  none.has_angular_velocity = none.has_linear_acceleration = none.has_orientation = false;
  CHECK(rejection(decode(runtime::InputKind::kImu, none)).find("no group present") != std::string::npos);
  auto nan = imu();
  nan.linear_acceleration[1] = std::numeric_limits<double>::quiet_NaN();
  CHECK(rejection(decode(runtime::InputKind::kImu, nan)).rfind("non_finite: imu_t.linear_acceleration[1]", 0) == 0);
  auto quat = imu();
  quat.orientation[0] = 2;
  CHECK(rejection(decode(runtime::InputKind::kImu, quat)).rfind("quaternion: imu_t.orientation", 0) == 0);
  auto cov = imu();
  cov.angular_velocity_covariance[0] = -1;  // ROS's "absent" marker must become has_* = false, not a covariance
  CHECK(rejection(decode(runtime::InputKind::kImu, cov)).rfind("covariance: imu_t.angular_velocity_covariance", 0) ==
        0);
  auto late = imu();
  late.utime = 0;
  CHECK(rejection(decode(runtime::InputKind::kImu, late)).rfind("invalid: imu_t.utime", 0) == 0);
  auto absent = imu();
  absent.has_orientation = false;
  absent.orientation[0] = std::numeric_limits<double>::quiet_NaN();  // an absent group is not read
  CHECK(rejection(decode(runtime::InputKind::kImu, absent)) == "accepted");
}

TEST_CASE("a GNSS fix decodes, no fix, an unknown status and impossible coordinates are refused") {
  const auto d = decode(runtime::InputKind::kGnss, gnss());
  REQUIRE(std::holds_alternative<engine::Event>(d));
  const auto& e = std::get<engine::GnssFix>(std::get<engine::Event>(d));
  CHECK(e.latitude == 40.0);
  CHECK(e.position_covariance(1, 1) == 4);
  CHECK_FALSE(e.velocity);
  auto no_fix = gnss();
  no_fix.status = sextant::gnss_t::STATUS_NO_FIX;
  CHECK(rejection(decode(runtime::InputKind::kGnss, no_fix)).rfind("no_fix", 0) == 0);
  auto status = gnss();
  status.status = 9;
  CHECK(rejection(decode(runtime::InputKind::kGnss, status)).rfind("invalid: gnss_t.status", 0) == 0);
  auto lat = gnss();
  lat.latitude = 91;
  CHECK(rejection(decode(runtime::InputKind::kGnss, lat)).rfind("invalid: gnss_t.latitude", 0) == 0);
  auto alt = gnss();
  alt.altitude = 1e308;  // finite, and nowhere on Earth
  CHECK(rejection(decode(runtime::InputKind::kGnss, alt)).rfind("invalid: gnss_t.altitude", 0) == 0);
  auto vel = gnss();
  vel.has_velocity = true;
  vel.velocity[0] = std::numeric_limits<double>::infinity();
  CHECK(rejection(decode(runtime::InputKind::kGnss, vel)).rfind("non_finite: gnss_t.velocity[0]", 0) == 0);
}
