// The simulated fleet (sim/simulator.hpp, `robots` > 1) against its own ground truth: every robot's odometry starts
// at the identity; a robot sighting is the range/bearing between the two robots' true poses within its noise; a
// correct inter-robot loop closure is T_from^-1 T_to of the truths within its noise, a wrong one far from it, and the
// wrong ones are the share asked for; the same seed gives the same bytes; one robot is not a fleet.
#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/lcm_log.hpp"
#include "sim/simulator.hpp"

#include <sextant/landmarks_t.hpp>
#include <sextant/loop_closure_t.hpp>
#include <sextant/odometry_t.hpp>

#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>

#include <unistd.h>

using namespace sextant;

namespace {

std::string temp(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("sextant_fleet_" + std::to_string(::getpid()) + "_" + name))
      .string();
}

tools::SimulationSummary run(const tools::SimulationOptions& o, const std::string& log) {
  runtime::LogWriter w(log);
  auto s = tools::simulate(o, w);
  w.flush();
  return s;
}

// The robots' true poses by source and utime.
using Truth = std::map<std::string, std::map<int64_t, Eigen::Isometry3d>>;
Truth truth_of(const tools::SimulationSummary& s) {
  Truth t;
  for (const auto& [source, poses] : s.fleet_truth)
    for (const auto& [utime, p] : poses) {
      Eigen::Isometry3d x = Eigen::Isometry3d::Identity();
      x.linear() = p.orientation.toRotationMatrix();
      x.translation() = p.position;
      t[source][utime] = x;
    }
  return t;
}

Eigen::Isometry3d iso(const double position[3], const double orientation[4]) {
  Eigen::Isometry3d x = Eigen::Isometry3d::Identity();
  x.linear() = Eigen::Quaterniond(orientation[0], orientation[1], orientation[2], orientation[3]).toRotationMatrix();
  x.translation() = Eigen::Vector3d(position[0], position[1], position[2]);
  return x;
}

double wrap(double a) { return std::remainder(a, 2 * M_PI); }

tools::SimulationOptions fleet_options(tools::Scenario scenario) {
  tools::SimulationOptions o;
  o.scenario = scenario;
  o.robots = 3;
  o.duration_s = 240;
  o.seed = 11;
  o.odometry_rate_hz = 100;  // the landmark stamps (10 Hz, offset 50 ms) fall on odometry stamps: truth at each
  o.wrong_loops = 0.2;
  o.sensors = 2, o.targets = 0;
  return o;
}

}  // namespace

TEST_CASE("fleet simulation: robot sightings are the range and bearing between the true poses") {
  for (const auto scenario : {tools::Scenario::kPlanar, tools::Scenario::kSpatial}) {
    CAPTURE(tools::scenario_name(scenario));
    const auto o = fleet_options(scenario);
    const auto log = temp("sightings.lcm");
    const auto s = run(o, log);
    const Truth truth = truth_of(s);
    REQUIRE(s.markers.size() == 3);
    std::map<int64_t, std::string> by_marker = s.markers;
    CHECK(by_marker.at(tools::fleet_marker(2)) == "robot2");
    int64_t sightings = 0;
    std::map<std::string, bool> first_seen;
    for (const auto& r : runtime::LogReader::read_all(log)) {
      if (r.channel == "ODOMETRY") {
        sextant::odometry_t m;
        REQUIRE(runtime::decode_message(r.data, m));
        if (first_seen.emplace(m.source, true).second) {  // each robot's odometry starts at the identity
          CHECK(iso(m.position, m.orientation).isApprox(Eigen::Isometry3d::Identity(), 1e-12));
          CHECK(!truth.at(m.source).begin()->second.isApprox(Eigen::Isometry3d::Identity(), 1e-3));
        }
      }
      if (r.channel != "LANDMARKS") continue;
      sextant::landmarks_t m;
      REQUIRE(runtime::decode_message(r.data, m));
      for (const auto& ob : m.observations) {
        CHECK(ob.id >= 0);
        if (ob.id < tools::fleet_marker(0)) continue;
        const auto seen = by_marker.find(ob.id);
        REQUIRE(seen != by_marker.end());
        CHECK(seen->second != m.source);
        const Eigen::Vector3d p =
            truth.at(m.source).at(m.utime).inverse() * truth.at(seen->second).at(m.utime).translation();
        const bool planar = scenario == tools::Scenario::kPlanar;
        const double range = planar ? std::hypot(p.x(), p.y()) : p.norm();
        CHECK(std::abs(ob.range - range) < 5 * o.range_sigma);
        CHECK(std::abs(wrap(ob.azimuth - std::atan2(p.y(), p.x()))) < 5 * o.bearing_sigma);
        if (!planar) CHECK(std::abs(ob.elevation - std::atan2(p.z(), std::hypot(p.x(), p.y()))) < 5 * o.bearing_sigma);
        ++sightings;
      }
    }
    CHECK(first_seen.size() == 3);
    CHECK(sightings == s.robot_sightings);
    CHECK(sightings > 100);
    std::remove(log.c_str());
  }
}

TEST_CASE("fleet simulation: inter-robot loops are T_from^-1 T_to of the truths, the wrong ones the share asked") {
  for (const auto scenario : {tools::Scenario::kPlanar, tools::Scenario::kSpatial}) {
    CAPTURE(tools::scenario_name(scenario));
    const auto o = fleet_options(scenario);
    const auto log = temp("loops.lcm");
    const auto s = run(o, log);
    const Truth truth = truth_of(s);
    int64_t inter = 0, wrong = 0;
    for (const auto& r : runtime::LogReader::read_all(log)) {
      if (r.channel != "LOOP_CLOSURES") continue;
      sextant::loop_closure_t m;
      REQUIRE(runtime::decode_message(r.data, m));
      if (m.source_to.empty()) continue;  // a loop of one robot
      CHECK(m.source_to != m.source);
      CHECK(m.utime_from <= m.utime_to);
      ++inter;
      const Eigen::Isometry3d expected =
          truth.at(m.source).at(m.utime_from).inverse() * truth.at(m.source_to).at(m.utime_to);
      const Eigen::Isometry3d error = expected.inverse() * iso(m.position, m.orientation);
      const double t = error.translation().norm(), a = Eigen::AngleAxisd(error.linear()).angle();
      if (t > 2.5) {
        ++wrong;
      } else {
        CHECK(t < 5 * std::sqrt(3.0) * o.loop_trans_sigma);
        CHECK(a < 5 * std::sqrt(3.0) * o.loop_rot_sigma);
      }
    }
    CHECK(inter == s.inter_robot_loops);
    CHECK(wrong == s.wrong_loops);
    REQUIRE(inter > 100);
    const double share = static_cast<double>(wrong) / static_cast<double>(inter);
    const double sd = std::sqrt(o.wrong_loops * (1 - o.wrong_loops) / static_cast<double>(inter));
    CAPTURE(inter);
    CHECK(std::abs(share - o.wrong_loops) < 4 * sd);
    std::remove(log.c_str());
  }
}

TEST_CASE("fleet simulation: deterministic by seed, no wrong loops unless asked, and one robot is not a fleet") {
  auto o = fleet_options(tools::Scenario::kPlanar);
  o.duration_s = 60;
  const auto a = temp("a.lcm"), b = temp("b.lcm");
  run(o, a);
  run(o, b);
  auto bytes = [](const std::string& f) {
    std::ifstream in(f, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  CHECK(bytes(a) == bytes(b));
  o.wrong_loops = 0;
  CHECK(run(o, a).wrong_loops == 0);
  o.robots = 1;
  const auto one = run(o, a);
  CHECK(one.markers.empty());
  CHECK(one.robot_sightings == 0);
  CHECK(one.inter_robot_loops == 0);
  o.robots = 2, o.imu_rate_hz = 100;
  CHECK_THROWS_AS(run(o, b), std::invalid_argument);
  for (const auto& f : {a, b}) std::remove(f.c_str());
}

TEST_CASE("fleet simulation: omitting the wrong loops leaves every other message as it was, byte for byte") {
  auto o = fleet_options(tools::Scenario::kPlanar);
  o.duration_s = 120;
  const auto with = temp("with.lcm"), without = temp("without.lcm");
  const auto s_with = run(o, with);
  o.omit_wrong_loops = true;
  const auto s_without = run(o, without);
  REQUIRE(s_with.wrong_loops > 5);
  CHECK(s_without.wrong_loops == s_with.wrong_loops);
  CHECK(s_without.inter_robot_loops == s_with.inter_robot_loops - s_with.wrong_loops);
  const Truth truth = truth_of(s_with);
  // Walk the two logs side by side: every record of the run without is the next record of the run with, and what the
  // run with has in between is wrong inter-robot loops only (checked against the truth, independently of the flag).
  const auto a = runtime::LogReader::read_all(with), b = runtime::LogReader::read_all(without);
  size_t i = 0;
  int64_t skipped = 0;
  const auto skip_wrong_loop = [&] {  // a[i] is not in the run without: it must be a wrong inter-robot loop
    REQUIRE(a[i].channel == "LOOP_CLOSURES");
    sextant::loop_closure_t m;
    REQUIRE(runtime::decode_message(a[i].data, m));
    REQUIRE_FALSE(m.source_to.empty());
    const Eigen::Isometry3d expected =
        truth.at(m.source).at(m.utime_from).inverse() * truth.at(m.source_to).at(m.utime_to);
    CHECK((expected.inverse() * iso(m.position, m.orientation)).translation().norm() > 2.5);
    ++skipped, ++i;
  };
  for (const auto& r : b) {
    while (i < a.size() && !(a[i].channel == r.channel && a[i].timestamp == r.timestamp && a[i].data == r.data))
      skip_wrong_loop();
    REQUIRE(i < a.size());
    ++i;
  }
  while (i < a.size()) skip_wrong_loop();
  CHECK(skipped == s_with.wrong_loops);
  for (const auto& f : {with, without}) std::remove(f.c_str());
}
