// Converters: a g2o graph through an LCM log reproduces its edges; TUM ground truth without noise gives odometry
// equal to the truth; bad rows are named by line; MRCLAM's command delay and sighting noise.
#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/lcm_log.hpp"
#include "estimators/graph/g2o_io.hpp"
#include "estimators/lie/se2.hpp"
#include "convert/g2o_converter.hpp"
#include "convert/mrclam_converter.hpp"
#include "eval/trajectory_io.hpp"
#include "convert/tum_converter.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>

using namespace sextant;

namespace {
std::string temp(const std::string& n) {
  return (std::filesystem::temp_directory_path() / ("sextant_conv_" + std::to_string(::getpid()) + "_" + n)).string();
}

template <class Event>
std::vector<Event> events_of(const std::string& log, runtime::InputKind kind, const std::string& channel) {
  std::vector<Event> out;
  for (const auto& r : runtime::LogReader::read_all(log)) {
    if (r.channel != channel) continue;
    auto d = runtime::decode_event(kind, r.data.data(), r.data.size());
    REQUIRE(std::holds_alternative<engine::Event>(d));
    out.push_back(std::get<Event>(std::get<engine::Event>(d)));
  }
  return out;
}
}  // namespace

TEST_CASE("g2o -> LCM log: odometry increments and loop closures reproduce the graph's edges") {
  for (const char* name : {"intel.g2o", "tinyGrid3D.g2o"}) {
    CAPTURE(name);
    const std::string path = std::string(SEXTANT_SHARED_DIR) + "/data/posegraph/" + name;
    const auto log = temp("g2o.lcm"), gt = temp("g2o_gt.txt");
    const auto r = tools::convert_g2o(path, log, gt);
    const auto g = graph::read_g2o(path);
    const auto odo = events_of<engine::Odometry>(log, runtime::InputKind::kOdometry, "ODOMETRY");
    const auto loops = events_of<engine::LoopClosure>(log, runtime::InputKind::kLoopClosures, "LOOP_CLOSURES");
    CHECK(static_cast<int64_t>(odo.size()) == r.odometry);
    CHECK(odo.size() == g.graph.variables().size());
    CHECK(odo.size() - 1 + loops.size() == g.graph.factors().size());  // the chain has one edge fewer than vertices
    // Every consecutive pair of odometry poses is the measurement of the chain edge between those vertices.
    for (const auto& f : g.graph.factors()) {
      const auto* rp = dynamic_cast<const graph::RelativePoseFactor*>(f.get());
      const auto a = g.graph.variables()[rp->variables()[0]].id, b = g.graph.variables()[rp->variables()[1]].id;
      if (b != a + 1) continue;
      const SE3 xa(odo[a].pose.orientation, odo[a].pose.position), xb(odo[b].pose.orientation, odo[b].pose.position);
      const SE3 z = rp->planar() ? rp->measurement2().to_se3() : rp->measurement3();
      CHECK((z.inverse() * xa.inverse() * xb).log().norm() < 1e-9);
    }
    // Loop closures: same relative pose and the utimes of their vertices (vertex k at start + k * 0.1 s).
    for (const auto& lc : loops) {
      CHECK(lc.utime_to > 0);
      CHECK((lc.utime_from - 1'700'000'000'000'000) % 100'000 == 0);
    }
    CHECK(tools::read_tum(gt).size() == g.graph.variables().size());
    std::remove(log.c_str());
    std::remove(gt.c_str());
  }
}

TEST_CASE("g2o information maps onto sextant's tangent") {
  Eigen::Matrix3d i2;
  i2 << 4, 1, 2, 1, 5, 3, 2, 3, 6;
  const auto m2 = tools::g2o_information_to_sextant(i2, true);
  CHECK(m2(0, 0) == 4);
  CHECK(m2(0, 5) == 2);
  CHECK(m2(5, 5) == 6);
  CHECK(m2(2, 2) == 0);
  // 3-D: the g2o rotation residual is qvec ~ phi / 2, so a rotation phi costs phi' (Omega_rr / 4) phi.
  Eigen::Matrix<double, 6, 6> i3 = Eigen::Matrix<double, 6, 6>::Identity() * 100;
  const auto m3 = tools::g2o_information_to_sextant(i3, false);
  CHECK(m3(0, 0) == 100);
  CHECK(m3(3, 3) == 25);
  const Eigen::Vector3d phi(0.001, -0.002, 0.0015);
  const SE3 e = SE3::exp((Vector6d() << 0, 0, 0, phi).finished());
  const Eigen::Vector3d qvec = e.rotation().quaternion().vec();
  CHECK(qvec.dot(100 * qvec) == doctest::Approx(phi.dot(m3.bottomRightCorner<3, 3>() * phi)).epsilon(1e-5));
}

TEST_CASE("TUM ground truth -> odometry: exact without noise, drifting with it, bad rows named") {
  const std::string gt = std::string(SEXTANT_SHARED_DIR) + "/data/tum/fr1_xyz/groundtruth.txt";
  const auto log = temp("tum.lcm");
  tools::TumConversionOptions o;
  o.trans_noise = o.rot_noise = o.yaw_drift = o.scale_drift = 0;
  o.min_sigma = 1e-9;
  o.frame_rate_hz = 0;  // one odometry message per ground-truth row, so that index k pairs them
  tools::convert_tum(gt, log, o);
  const auto truth = tools::read_tum(gt);
  auto odo = events_of<engine::Odometry>(log, runtime::InputKind::kOdometry, "ODOMETRY");
  REQUIRE(odo.size() > 1000);
  double worst = 0;
  for (size_t k = 0; k < odo.size(); k += 97)
    worst = std::max(worst, (odo[k].pose.position - truth[k].pose.position).norm());
  CHECK(worst < 1e-6);
  o = tools::TumConversionOptions{};
  tools::convert_tum(gt, log, o);
  odo = events_of<engine::Odometry>(log, runtime::InputKind::kOdometry, "ODOMETRY");
  const double final_error = (odo.back().pose.position - truth.back().pose.position).norm();
  CHECK(final_error > 1e-3);
  CHECK(final_error < 0.5);
  const auto bad = temp("bad.txt");
  std::ofstream(bad) << "1.0 0 0 0 0 0 0 1\n2.0 0 0 zero 0 0 0 1\n";
  CHECK_THROWS_WITH(tools::convert_tum(bad, log, o), doctest::Contains(":2: not a number"));
  std::remove(bad.c_str());
  std::remove(log.c_str());
}

TEST_CASE(
    "MRCLAM: landmark, robot and unknown-barcode sightings as the data set defines them, and odometry starts on the "
    "truth") {
  const std::string dir = std::string(SEXTANT_SHARED_DIR) + "/data/landmarks/MRCLAM_Dataset7";
  const auto log = temp("mrclam.lcm"), gt = temp("mrclam_gt.txt");
  const auto r3 = tools::convert_mrclam(dir, 3, log, gt);
  CHECK(r3.landmark_observations == 4425);
  CHECK(r3.robot_sightings == 965);
  CHECK(r3.unknown_barcodes == 9);
  const auto truth = tools::read_tum(gt);
  CHECK(truth.size() == 53545);
  const auto odo = events_of<engine::Odometry>(log, runtime::InputKind::kOdometry, "ODOMETRY");
  const auto sightings = events_of<engine::LandmarkSightings>(log, runtime::InputKind::kLandmarks, "LANDMARKS");
  REQUIRE(odo.size() > 50000);
  // The first odometry pose is the ground truth nearest its stamp (within the Vicon's ~16 ms step).
  size_t g = 0;
  while (g + 1 < truth.size() && truth[g + 1].t <= odo.front().utime * 1e-6) ++g;
  CHECK((odo.front().pose.position - truth[g].pose.position).norm() < 0.05);
  for (const auto& s : sightings)
    for (const auto& o : s.observations) CHECK((o.id >= 6 && o.id <= 20));
  // Odometry utimes strictly increase (duplicated stamps merged).
  bool increasing = true;
  for (size_t k = 1; k < odo.size(); ++k) increasing = increasing && odo[k].utime > odo[k - 1].utime;
  CHECK(increasing);
  CHECK_THROWS_WITH(tools::convert_mrclam(dir, 7, log, ""), doctest::Contains("numbered 1 to 5"));
  std::remove(log.c_str());
  std::remove(gt.c_str());
}

TEST_CASE(
    "MRCLAM: the command delay shifts the odometry stamps only, and brings the commanded turns closer to the truth") {
  const std::string dir = std::string(SEXTANT_SHARED_DIR) + "/data/landmarks/MRCLAM_Dataset7";
  const auto log0 = temp("mrclam_d0.lcm"), log1 = temp("mrclam_d1.lcm"), gt = temp("mrclam_d_gt.txt");
  tools::MrclamOptions immediate;
  immediate.command_delay_s = 0;
  const tools::MrclamOptions delayed;  // the default delay
  REQUIRE(delayed.command_delay_s > 0.1);
  tools::convert_mrclam(dir, 4, log0, "", immediate);
  tools::convert_mrclam(dir, 4, log1, gt, delayed);
  const auto odo0 = events_of<engine::Odometry>(log0, runtime::InputKind::kOdometry, "ODOMETRY");
  const auto odo1 = events_of<engine::Odometry>(log1, runtime::InputKind::kOdometry, "ODOMETRY");
  REQUIRE(odo0.size() == odo1.size());
  REQUIRE(odo0.size() > 60000);
  const auto shift = static_cast<int64_t>(std::llround(delayed.command_delay_s * 1e6));
  bool shifted = true;
  for (size_t k = 0; k < odo0.size(); ++k) shifted = shifted && odo1[k].utime - odo0[k].utime == shift;
  CHECK(shifted);
  // Sightings keep their stamps; their covariance follows the options (range sigma proportional to the range).
  const auto s0 = events_of<engine::LandmarkSightings>(log0, runtime::InputKind::kLandmarks, "LANDMARKS");
  const auto s1 = events_of<engine::LandmarkSightings>(log1, runtime::InputKind::kLandmarks, "LANDMARKS");
  REQUIRE(s0.size() == s1.size());
  REQUIRE(!s1.empty());
  CHECK(s0.front().utime == s1.front().utime);
  CHECK(s0.back().utime == s1.back().utime);
  const auto& ob = s1.front().observations.front();
  CHECK(ob.covariance(0, 0) == doctest::Approx(std::pow(delayed.range_sigma_per_metre * ob.range, 2)));
  CHECK(ob.covariance(1, 1) == doctest::Approx(delayed.bearing_sigma * delayed.bearing_sigma));
  // Heading change of the odometry over 1 s windows against the Vicon truth's over the same stamps: the delayed
  // commands match the truth's turns better (the robots carry a command out ~0.15-0.2 s after its stamp).
  const auto truth = tools::read_tum(gt);
  auto yaw_at = [&](double t) {
    auto it = std::lower_bound(truth.begin(), truth.end(), t, [](const auto& p, double x) { return p.t < x; });
    if (it == truth.begin() || it == truth.end()) return std::optional<double>{};
    return std::optional<double>{SE2::from_se3(SE3(it->pose.orientation, it->pose.position)).angle()};
  };
  auto yaw_error = [&](const std::vector<engine::Odometry>& odo) {
    double sum = 0;
    int n = 0;
    for (size_t k = 0; k + 65 < odo.size(); k += 65) {
      const double t0 = odo[k].utime * 1e-6, t1 = odo[k + 65].utime * 1e-6;
      const auto a = yaw_at(t0), b = yaw_at(t1);
      if (!a || !b) continue;
      const double d_odo =
          wrap_angle(SE2::from_se3(SE3(odo[k + 65].pose.orientation, odo[k + 65].pose.position)).angle() -
                     SE2::from_se3(SE3(odo[k].pose.orientation, odo[k].pose.position)).angle());
      sum += std::pow(wrap_angle(d_odo - wrap_angle(*b - *a)), 2);
      ++n;
    }
    REQUIRE(n > 500);
    return std::sqrt(sum / n);
  };
  const double e0 = yaw_error(odo0), e1 = yaw_error(odo1);
  CAPTURE(e0);
  CAPTURE(e1);
  CHECK(e1 < 0.8 * e0);
  tools::MrclamOptions bad;
  bad.command_delay_s = std::nan("");
  CHECK_THROWS_WITH(tools::convert_mrclam(dir, 4, log0, "", bad), doctest::Contains("delay"));
  for (const auto& f : {log0, log1, gt}) std::remove(f.c_str());
}

TEST_CASE("MRCLAM fleet: robots merged in time order, each odometry from the identity, robot sightings kept by id") {
  const std::string dir = std::string(SEXTANT_SHARED_DIR) + "/data/landmarks/MRCLAM_Dataset7";
  const auto log = temp("mrclam_fleet.lcm"), prefix = temp("mrclam_fleet_gt_");
  const auto r = tools::convert_mrclam_fleet(dir, {1, 2, 3, 4, 5}, log, prefix);
  // Robot sightings per robot in the raw files: 650, 700, 965, 555, 1336 (barcodes 5, 14, 41, 32, 23).
  CHECK(r.robot_sightings == 4206);
  CHECK(r.robot_sightings_kept == 4206);
  const auto odo = events_of<engine::Odometry>(log, runtime::InputKind::kOdometry, "ODOMETRY");
  const auto sightings = events_of<engine::LandmarkSightings>(log, runtime::InputKind::kLandmarks, "LANDMARKS");
  CHECK(static_cast<int64_t>(odo.size()) == r.odometry);
  std::map<std::string, engine::Odometry> first;
  for (const auto& o : odo) first.try_emplace(o.source, o);
  REQUIRE(first.size() == 5);
  for (const auto& [source, o] : first) {
    CAPTURE(source);
    CHECK(o.pose.position.norm() == 0.0);
    CHECK(o.pose.orientation.angularDistance(Eigen::Quaterniond::Identity()) == 0.0);
  }
  // Robot2_Measurement.dat: "1248446191.119  32  1.247  -0.068", barcode 32 = subject 4.
  int64_t robots_seen = 0, landmarks_seen = 0;
  bool found = false;
  for (const auto& s : sightings)
    for (const auto& ob : s.observations) {
      (ob.id <= 5 ? robots_seen : landmarks_seen) += 1;
      if (s.source == "robot2" && s.utime == 1248446191119000 && ob.id == 4)
        found = ob.range == doctest::Approx(1.247) && ob.azimuth == doctest::Approx(-0.068);
    }
  CHECK(found);
  CHECK(robots_seen == 4206);
  CHECK(landmarks_seen == r.landmark_observations);
  // Time order across robots.
  int64_t last = 0;
  bool ordered = true;
  for (const auto& rec : runtime::LogReader::read_all(log))
    ordered = ordered && rec.timestamp >= last, last = rec.timestamp;
  CHECK(ordered);
  // Ground truth files: one TUM per robot (robot 3's as long as the single-robot conversion's) and the landmarks.
  CHECK(tools::read_tum(prefix + "robot3.txt").size() == 53545);
  std::ifstream lm(prefix + "landmarks.txt");
  std::string line;
  int rows = 0;
  while (std::getline(lm, line)) rows += !line.empty() && line[0] != '#';
  CHECK(rows == 15);
  std::remove(log.c_str());
  for (const char* f : {"robot1.txt", "robot2.txt", "robot3.txt", "robot4.txt", "robot5.txt", "landmarks.txt"})
    std::remove((prefix + f).c_str());
}

TEST_CASE("MRCLAM fleet: sightings of robots outside the log are counted, not kept, and robot lists parse") {
  const std::string dir = std::string(SEXTANT_SHARED_DIR) + "/data/landmarks/MRCLAM_Dataset7";
  const auto log = temp("mrclam_fleet23.lcm");
  const auto r = tools::convert_mrclam_fleet(dir, {2, 3}, log, "");
  CHECK(r.robot_sightings == 700 + 965);
  CHECK(r.robot_sightings_kept > 0);
  CHECK(r.robot_sightings_kept < r.robot_sightings);
  for (const auto& s : events_of<engine::LandmarkSightings>(log, runtime::InputKind::kLandmarks, "LANDMARKS"))
    for (const auto& ob : s.observations) CHECK((ob.id == 2 || ob.id == 3 || ob.id >= 6));
  std::remove(log.c_str());
  CHECK(tools::parse_mrclam_robots("1-5") == std::vector<int>{1, 2, 3, 4, 5});
  CHECK(tools::parse_mrclam_robots("1,3,5") == std::vector<int>{1, 3, 5});
  CHECK(tools::parse_mrclam_robots("2-3,5") == std::vector<int>{2, 3, 5});
  for (const char* bad : {"", "0-2", "1-6", "3-1", "1,1", "a", "1-", "1-2x"})
    CHECK_THROWS_AS(tools::parse_mrclam_robots(bad), std::invalid_argument);
  CHECK_THROWS_WITH(tools::convert_mrclam_fleet(dir, {1, 1}, log, ""), doctest::Contains("twice"));
}
