// `sextant simulate` with IMU and GNSS on: the other streams are byte for byte those of the same run without them,
// and the inertial filter fed with the simulated IMU (prediction), GNSS (antenna position through the tangent plane,
// gated; velocity) and the wheel odometry's velocity follows the true trajectory, drifts through GNSS outages at most
// half as much as the odometry alone, and is not pulled by multipath outliers.
#include "sim/simulator.hpp"

#include "estimators/geodesy/local_tangent_plane.hpp"
#include "estimators/inertial/error_state_ekf.hpp"

#include <doctest/doctest.h>

#include <sextant/gnss_t.hpp>
#include <sextant/imu_t.hpp>
#include <sextant/odometry_t.hpp>

#include <cmath>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

using namespace sextant;
using namespace sextant::tools;

namespace {

std::string temp_log(const std::string& name) { return (std::filesystem::temp_directory_path() / name).string(); }

std::vector<runtime::LogRecord> run(const SimulationOptions& o, const std::string& name, SimulationSummary* summary) {
  const std::string path = temp_log(name);
  {
    runtime::LogWriter w(path);
    *summary = simulate(o, w);
    w.flush();
  }
  auto records = runtime::LogReader::read_all(path);
  std::filesystem::remove(path);
  return records;
}

}  // namespace

TEST_CASE("simulate spatial with IMU and GNSS: other streams unchanged, and the inertial filter follows the truth") {
  SimulationOptions o;
  o.scenario = Scenario::kSpatial;
  o.seed = 5;
  o.duration_s = 180;
  SimulationSummary plain_summary, summary;
  const auto plain = run(o, "sextant_sim_plain.lcm", &plain_summary);
  o.imu_rate_hz = 200;
  o.gnss_rate_hz = 5;
  o.gnss.outage_period_s = 90;
  o.gnss.outage_duration_s = 30;
  o.gnss.outlier_probability = 0.05;
  o.gnss.lever_arm = Eigen::Vector3d(0.2, 0, 0.8);
  const auto records = run(o, "sextant_sim_inertial.lcm", &summary);

  std::vector<runtime::LogRecord> others;
  for (const auto& r : records)
    if (r.channel != "IMU" && r.channel != "GNSS") others.push_back(r);
  REQUIRE(others.size() == plain.size());
  for (size_t i = 0; i < plain.size(); ++i)
    REQUIRE((others[i].channel == plain[i].channel && others[i].data == plain[i].data));
  CHECK(summary.imu == 180 * 200 + 1);
  CHECK(summary.gnss == 2 * 60 * 5 + 1);  // 60 s of each 90 s period, and the fix at t = 180 s
  CHECK(summary.gnss_outliers > 0);

  // The filter: started at the true pose and speed, biases unknown.
  std::map<int64_t, engine::Pose> truth(summary.robot_truth.begin(), summary.robot_truth.end());
  const geodesy::LocalTangentPlane plane(o.gnss.datum);
  inertial::EskfOptions eo;
  eo.noise = o.imu.noise;
  inertial::ErrorStateEkf f(eo);
  const auto first = summary.robot_truth[0], second = summary.robot_truth[1];
  inertial::EskfState x0;
  x0.p = first.second.position;
  x0.q = first.second.orientation;
  x0.v = (second.second.position - first.second.position) / (static_cast<double>(second.first - first.first) * 1e-6);
  inertial::ErrorStateEkf::Matrix15 P0 = inertial::ErrorStateEkf::Matrix15::Zero();
  P0.diagonal() << Eigen::Vector3d::Constant(0.25), Eigen::Vector3d::Constant(0.01), Eigen::Vector3d::Constant(1e-4),
      Eigen::Vector3d::Constant(0.05 * 0.05), Eigen::Vector3d::Constant(0.005 * 0.005);
  f.initialize(static_cast<double>(first.first) * 1e-6, x0, P0);

  int gated = 0, fused = 0;
  double sq_with_gnss = 0, worst_in_outage = 0;
  int n_with_gnss = 0;
  const double t0 = static_cast<double>(o.start_utime) * 1e-6;
  // Per outage (60-90 s and 150-180 s), at its first and last odometry time: the filter's and the odometry's poses.
  struct Mark {
    Eigen::Vector3d filter, odometry_p;
    Eigen::Quaterniond odometry_q;
  };
  std::map<int64_t, Mark> marks;
  const std::vector<int64_t> mark_times = {o.start_utime + 60'000'000, o.start_utime + 89'980'000,
                                           o.start_utime + 150'000'000, o.start_utime + 179'980'000};
  std::optional<odometry_t> previous_odometry;
  for (const auto& r : records) {
    if (r.channel == "ODOMETRY") {
      // Wheel odometry as a body velocity: the increment since the previous message over its duration.
      odometry_t m;
      REQUIRE(runtime::decode_message(r.data, m));
      if (previous_odometry) {
        const odometry_t& a = *previous_odometry;
        const double dt = static_cast<double>(m.utime - a.utime) * 1e-6;
        const Eigen::Quaterniond qa(a.orientation[0], a.orientation[1], a.orientation[2], a.orientation[3]);
        const Eigen::Vector3d v = qa.conjugate() * (Eigen::Vector3d(m.position) - Eigen::Vector3d(a.position)) / dt;
        const Eigen::Matrix3d R = Eigen::Map<const Eigen::Matrix<double, 6, 6, Eigen::RowMajor>>(m.increment_covariance)
                                          .topLeftCorner<3, 3>() /
                                      (dt * dt) +
                                  Eigen::Matrix3d::Identity() * 1e-4;
        f.propagate_to(static_cast<double>(m.utime) * 1e-6);
        f.update_body_velocity(v, R, inertial::SensorMounting{});
      }
      previous_odometry = m;
      for (int64_t mt : mark_times)
        if (m.utime == mt)
          marks[mt] = {f.state().p, Eigen::Vector3d(m.position),
                       Eigen::Quaterniond(m.orientation[0], m.orientation[1], m.orientation[2], m.orientation[3])};
    } else if (r.channel == "IMU") {
      imu_t m;
      REQUIRE(runtime::decode_message(r.data, m));
      const double t = static_cast<double>(m.utime) * 1e-6;
      f.add_imu(t, inertial::imu_to_body(o.imu.mounting, Eigen::Vector3d(m.angular_velocity),
                                         Eigen::Vector3d(m.linear_acceleration)));
      const auto tr = truth.find(m.utime);
      if (tr == truth.end() || t - t0 < 10) continue;  // errors after 10 s of convergence
      const double e = (f.state().p - tr->second.position).norm();
      const bool outage =
          std::fmod(t - t0, o.gnss.outage_period_s) >= o.gnss.outage_period_s - o.gnss.outage_duration_s;
      if (outage) {
        worst_in_outage = std::max(worst_in_outage, e);
      } else {
        sq_with_gnss += e * e;
        ++n_with_gnss;
      }
    } else if (r.channel == "GNSS") {
      gnss_t m;
      REQUIRE(runtime::decode_message(r.data, m));
      f.propagate_to(static_cast<double>(m.utime) * 1e-6);
      const Eigen::Vector3d enu = plane.to_enu({m.latitude, m.longitude, m.altitude});
      const auto u = f.update_gnss_position(enu, Eigen::Map<const Eigen::Matrix3d>(m.position_covariance),
                                            o.gnss.lever_arm, inertial::kAllFields, 16.27);  // chi2(3) 99.9 %
      u.accepted ? ++fused : ++gated;
      f.update_gnss_velocity(Eigen::Vector3d(m.velocity), Eigen::Map<const Eigen::Matrix3d>(m.velocity_covariance),
                             o.gnss.lever_arm);
    }
  }
  const double rms = std::sqrt(sq_with_gnss / n_with_gnss);
  // Drift over each outage, both aligned at its start: the filter's displacement against the truth's, and the
  // odometry's displacement (rotated into the world by the true heading at the start) against the truth's.
  REQUIRE(marks.size() == 4);
  double filter_drift = 0, odometry_drift = 0;
  for (size_t k = 0; k < 4; k += 2) {
    const int64_t s0 = mark_times[k], s1 = mark_times[k + 1];
    const Eigen::Vector3d truth_move = truth.at(s1).position - truth.at(s0).position;
    const Eigen::Vector3d odo_move =
        truth.at(s0).orientation * (marks[s0].odometry_q.conjugate() * (marks[s1].odometry_p - marks[s0].odometry_p));
    filter_drift = std::max(filter_drift, (marks[s1].filter - marks[s0].filter - truth_move).norm());
    odometry_drift = std::max(odometry_drift, (odo_move - truth_move).norm());
  }
  MESSAGE(
      "simulated spatial 180 s, IMU 200 Hz + wheel odometry 50 Hz + GNSS 5 Hz (30 s outages, 5 % multipath): "
      "position RMS with GNSS ",
      rms, " m; worst error in an outage ", worst_in_outage,
      " m; drift over an outage: "
      "filter ",
      filter_drift, " m, odometry alone ", odometry_drift, " m; GNSS fused ", fused, ", gated ", gated, " (",
      summary.gnss_outliers, " outliers simulated)");
  CHECK(rms < 0.3);
  CHECK(filter_drift <= 0.5 * odometry_drift);
  CHECK(worst_in_outage < 1);
  CHECK(gated >= summary.gnss_outliers / 2);
  CHECK(gated <= summary.gnss_outliers + 5);
}
