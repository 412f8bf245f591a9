// Codec: event -> LCM bytes -> event round trips, and every rejection naming its field.
#include "daemon/runtime/codec.hpp"

#include "daemon/runtime/encode_message.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <vector>

using namespace sextant;
using runtime::Decoded;
using runtime::InputKind;
using runtime::Rejection;

namespace {

engine::Matrix6 spd6(double scale) {
  engine::Matrix6 a;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) a(i, j) = std::sin(1.0 + i * 7 + j * 3);
  return scale * (a * a.transpose() + engine::Matrix6::Identity());
}

engine::Odometry sample_odometry() {
  engine::Odometry o;
  o.utime = 1'700'000'000'123'456;
  o.source = "wheel";
  o.pose.position = {1.5, -2.25, 0.125};
  o.pose.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()));
  o.covariance = spd6(0.01);
  o.increment_covariance = spd6(0.001);
  return o;
}

Rejection rejection(const Decoded& d) {
  REQUIRE(std::holds_alternative<Rejection>(d));
  return std::get<Rejection>(d);
}

}  // namespace

TEST_CASE("odometry survives encode and decode exactly") {
  const auto o = sample_odometry();
  const auto bytes = encode(runtime::to_message(o, "test", 42));
  const Decoded d = runtime::decode_event(InputKind::kOdometry, bytes.data(), bytes.size());
  REQUIRE(std::holds_alternative<engine::Event>(d));
  const auto& back = std::get<engine::Odometry>(std::get<engine::Event>(d));
  CHECK(back.utime == o.utime);
  CHECK(back.source == "wheel");
  CHECK((back.pose.position - o.pose.position).norm() == 0.0);
  CHECK(back.pose.orientation.angularDistance(o.pose.orientation) < 1e-12);
  CHECK((back.covariance - o.covariance).norm() == 0.0);
  REQUIRE(back.increment_covariance.has_value());
  CHECK((*back.increment_covariance - *o.increment_covariance).norm() == 0.0);
  CHECK_FALSE(back.twist.has_value());
}

TEST_CASE("landmark sightings, bearing scans and loop closures round trip") {
  engine::LandmarkSightings s;
  s.utime = 5;
  s.source = "r1";
  s.observations.push_back({7, 3.5, 0.25, -0.1, Eigen::Matrix3d::Identity() * 0.01});
  s.observations.push_back({-1, 1.0, -2.0, 0.3, Eigen::Matrix3d::Identity() * 0.02});
  auto b1 = encode(runtime::to_message(s, "t", 0));
  auto d1 = runtime::decode_event(InputKind::kLandmarks, b1.data(), b1.size());
  const auto& s2 = std::get<engine::LandmarkSightings>(std::get<engine::Event>(d1));
  REQUIRE(s2.observations.size() == 2);
  CHECK(s2.observations[0].id == 7);
  CHECK(s2.observations[1].id == -1);
  CHECK(s2.observations[1].azimuth == -2.0);
  CHECK(s2.observations[1].elevation == 0.3);

  engine::BearingScan scan;
  scan.utime = 9;
  scan.sensor_id = 3;
  scan.scan_id = 77;
  scan.sensor_position = {30, 0, 0.1};
  scan.detections.push_back({0.5, 0.1, 0.005, 0.005});
  auto b2 = encode(runtime::to_message(scan, "t", 0));
  auto d2 = runtime::decode_event(InputKind::kBearings, b2.data(), b2.size());
  const auto& scan2 = std::get<engine::BearingScan>(std::get<engine::Event>(d2));
  CHECK(scan2.scan_id == 77);
  CHECK(scan2.sensor_position.x() == 30);
  CHECK(scan2.detections.at(0).sigma_azimuth == 0.005);

  engine::LoopClosure lc;
  lc.utime = 100;
  lc.source = "r1";
  lc.utime_from = 10;
  lc.utime_to = 90;
  lc.relative.position = {1, 2, 3};
  lc.information = spd6(100);
  lc.matcher = "sim";
  lc.score = 0.9;
  auto b3 = encode(runtime::to_message(lc, "t", 0));
  auto d3 = runtime::decode_event(InputKind::kLoopClosures, b3.data(), b3.size());
  const auto& lc2 = std::get<engine::LoopClosure>(std::get<engine::Event>(d3));
  CHECK(lc2.utime_to == 90);
  CHECK((lc2.information - lc.information).norm() == 0.0);
}

TEST_CASE("outputs convert to messages and back") {
  engine::Targets t;
  t.utime = 3;
  t.scan_id = 4;
  t.cost_kind = "renyi";
  t.sensor_ids = {1, 2, 3};
  engine::Target x;
  x.position = {1, 2, 3};
  x.covariance = Eigen::Matrix3d::Identity();
  x.detection_indices = {0, -1, 2};
  x.cost = -12.5;
  t.targets.push_back(x);
  const auto back = runtime::to_output(runtime::to_message(t, "s", 1));
  CHECK(back.sensor_ids == t.sensor_ids);
  CHECK(back.targets.at(0).detection_indices == x.detection_indices);
  CHECK(back.targets.at(0).cost == -12.5);

  engine::FusedPose f;
  f.utime = 8;
  f.source = "r";
  f.estimator = "ekf";
  f.covariance = spd6(1);
  const auto fm = runtime::to_message(f, "s", 9);
  CHECK(fm.seq == 9);
  CHECK(fm.sender == "s");
  CHECK(fm.orientation[0] == 1.0);  // identity quaternion, w first
  CHECK((runtime::to_output(fm).covariance - f.covariance).norm() == 0.0);
}

TEST_CASE("non-finite fields are rejected with the field's name") {
  auto m = runtime::to_message(sample_odometry(), "t", 0);
  m.position[1] = std::numeric_limits<double>::quiet_NaN();
  const auto& r = rejection(runtime::to_event(m));
  CHECK(r.reason == "non_finite");
  CHECK(r.message == "odometry_t.position[1]: not finite (nan)");

  auto m2 = runtime::to_message(sample_odometry(), "t", 0);
  m2.covariance[7] = std::numeric_limits<double>::infinity();
  CHECK(rejection(runtime::to_event(m2)).message.find("odometry_t.covariance[7]") == 0);
}

TEST_CASE("names longer than 256 characters or holding a control character are rejected with the field's name") {
  for (const std::string& name :
       {std::string(257, 'r'), std::string("robot\n1"), std::string("a\0b", 3), std::string("robot\x7f")}) {
    CAPTURE(name.size());
    auto m = runtime::to_message(sample_odometry(), "t", 0);
    m.source = name;
    const auto& r = rejection(runtime::to_event(m));
    CHECK(r.reason == "invalid");
    CHECK(r.message.rfind("odometry_t.source: ", 0) == 0);
  }
  auto ok = runtime::to_message(sample_odometry(), "t", 0);
  ok.source = std::string(256, 'r') + "";
  CHECK(std::holds_alternative<engine::Event>(runtime::to_event(ok)));
  ok.source = "robot 1 (Ünïcode)";  // spaces and UTF-8 are names
  CHECK(std::holds_alternative<engine::Event>(runtime::to_event(ok)));
}

TEST_CASE("non-positive-definite and asymmetric covariances are rejected") {
  auto m = runtime::to_message(sample_odometry(), "t", 0);
  for (double& v : m.covariance) v = 0;
  m.covariance[0] = 1;  // rank one: not positive definite
  const auto& r = rejection(runtime::to_event(m));
  CHECK(r.reason == "covariance");
  CHECK(r.message.find("odometry_t.covariance: not positive definite") == 0);

  auto m2 = runtime::to_message(sample_odometry(), "t", 0);
  m2.covariance[1] += 0.5;
  CHECK(rejection(runtime::to_event(m2)).message == "odometry_t.covariance: not symmetric");

  auto m3 = runtime::to_message(sample_odometry(), "t", 0);
  for (double& v : m3.increment_covariance) v = 0;
  CHECK(rejection(runtime::to_event(m3)).message.find("odometry_t.increment_covariance") == 0);
}

TEST_CASE("planar messages need only the x, y, yaw block to be positive definite") {
  auto o = sample_odometry();
  o.planar = true;
  o.covariance = engine::Matrix6::Zero();
  o.covariance(0, 0) = o.covariance(1, 1) = 0.1;
  o.covariance(5, 5) = 0.01;
  o.increment_covariance.reset();
  CHECK(std::holds_alternative<engine::Event>(runtime::to_event(runtime::to_message(o, "t", 0))));
  o.planar = false;
  CHECK(rejection(runtime::to_event(runtime::to_message(o, "t", 0))).reason == "covariance");
}

TEST_CASE("a quaternion that is not unit is rejected") {
  auto m = runtime::to_message(sample_odometry(), "t", 0);
  m.orientation[0] = 2.0;
  CHECK(rejection(runtime::to_event(m)).reason == "quaternion");
}

TEST_CASE("bytes of the wrong type, truncated bytes and garbage are told apart") {
  const auto bytes = encode(runtime::to_message(sample_odometry(), "t", 0));
  CHECK(rejection(runtime::decode_event(InputKind::kLandmarks, bytes.data(), bytes.size())).reason == "fingerprint");
  CHECK(rejection(runtime::decode_event(InputKind::kOdometry, bytes.data(), bytes.size() / 2)).reason == "decode");
  const uint8_t junk[3] = {1, 2, 3};
  CHECK(rejection(runtime::decode_event(InputKind::kOdometry, junk, sizeof junk)).reason == "decode");
}

TEST_CASE("huge arrays are refused before use") {
  sextant::bearing_scan_t m{};
  m.utime = 1;
  m.num_detections = runtime::kMaxDetectionsPerScan + 1;
  m.detections.resize(static_cast<size_t>(m.num_detections), sextant::bearing_detection_t{0, 0, 0.01, 0.01});
  const auto& r = rejection(runtime::to_event(m));
  CHECK(r.reason == "too_large");
  CHECK(r.message.find("bearing_scan_t.num_detections") == 0);
}

TEST_CASE("bearing detections need positive standard deviations and valid elevation") {
  engine::BearingScan s;
  s.utime = 1;
  s.detections.push_back({0.1, 0.2, 0.0, 0.01});
  CHECK(rejection(runtime::to_event(runtime::to_message(s, "t", 0))).message ==
        "bearing_scan_t.detections[0].sigma_azimuth: not positive");
  s.detections[0] = {0.1, 2.0, 0.01, 0.01};
  CHECK(rejection(runtime::to_event(runtime::to_message(s, "t", 0))).message.find("elevation: outside") !=
        std::string::npos);
}
