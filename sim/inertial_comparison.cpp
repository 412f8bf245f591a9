#include "sim/inertial_comparison.hpp"

#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/lcm_log.hpp"
#include "estimators/geodesy/local_tangent_plane.hpp"
#include "estimators/inertial/error_state_ekf.hpp"
#include "estimators/inertial/inertial_smoother.hpp"
#include "estimators/spd_matrix.hpp"

#include <sextant/gnss_t.hpp>
#include <sextant/imu_t.hpp>
#include <sextant/odometry_t.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace sextant::tools {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

SE3 to_se3(const double* position, const double* orientation) {
  const Eigen::Quaterniond q(orientation[0], orientation[1], orientation[2], orientation[3]);
  return SE3(SO3::from_unit_quaternion(q.normalized()), Eigen::Vector3d(position[0], position[1], position[2]));
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// The filter's pose NEES against the truth (InertialComparison::filter_nees).
double pose_nees(const inertial::ErrorStateEkf& f, const engine::Pose& truth) {
  using E = inertial::ErrorStateEkf;
  const Eigen::AngleAxisd rotation(f.state().q.conjugate() * truth.orientation.normalized());
  Eigen::Matrix<double, 6, 1> e;
  e << truth.position - f.state().p, rotation.angle() * rotation.axis();
  Eigen::Matrix<double, 6, 6> P;
  P << f.covariance().block<3, 3>(E::kP, E::kP), f.covariance().block<3, 3>(E::kP, E::kTheta),
      f.covariance().block<3, 3>(E::kTheta, E::kP), f.covariance().block<3, 3>(E::kTheta, E::kTheta);
  return e.dot(P.ldlt().solve(e));
}

// Position errors of one estimate at the odometry times: RMS overall and in outages, drift over each outage.
struct Scorer {
  double sq = 0, sq_outage = 0, worst_with_gnss = 0, drift = 0;
  int n = 0, n_outage = 0;
  std::optional<Eigen::Vector3d> outage_start, outage_last;

  void add(const Eigen::Vector3d& e, bool outage, bool settled_gnss) {
    sq += e.squaredNorm(), ++n;
    if (outage) {
      sq_outage += e.squaredNorm(), ++n_outage;
      if (!outage_start) outage_start = e;
      outage_last = e;
    } else {
      close_outage();
      if (settled_gnss) worst_with_gnss = std::max(worst_with_gnss, e.head<2>().norm());
    }
  }
  void close_outage() {
    if (outage_start) drift = std::max(drift, (*outage_last - *outage_start).norm());
    outage_start.reset(), outage_last.reset();
  }
  InertialScore score() {
    close_outage();
    InertialScore s;
    s.ate = n ? std::sqrt(sq / n) : 0;
    s.ate_outage = n_outage ? std::sqrt(sq_outage / n_outage) : 0;
    s.drift = drift, s.worst_with_gnss = worst_with_gnss;
    return s;
  }
};

SimulationOptions simulation_options(const InertialComparisonOptions& o) {
  SimulationOptions s;
  s.scenario = Scenario::kSpatial;
  s.seed = o.seed;
  s.duration_s = o.duration_s;
  s.imu_rate_hz = 200;
  s.gnss_rate_hz = 5;
  s.gnss.outage_period_s = o.outage_period_s;
  s.gnss.outage_duration_s = o.outage_duration_s;
  s.gnss.outlier_probability = o.outlier_probability;
  s.gnss.lever_arm = Eigen::Vector3d(0.2, 0, 0.8);
  return s;
}

std::vector<runtime::LogRecord> simulate_records(const SimulationOptions& o, SimulationSummary& summary) {
  const std::string path =
      (std::filesystem::temp_directory_path() / ("sextant_inertial_comparison_" + std::to_string(o.seed) + ".lcm"))
          .string();
  {
    runtime::LogWriter w(path);
    summary = simulate(o, w);
    w.flush();
  }
  auto records = runtime::LogReader::read_all(path);
  std::filesystem::remove(path);
  return records;
}

// The filter as tests/sim/test_simulator_inertial.cpp runs it: odometry as a body velocity (the increment over its
// duration), GNSS position behind the chi-square(3) 99.9 % gate, GNSS velocity.
struct FilterRun {
  inertial::ErrorStateEkf f;
  std::optional<odometry_t> previous;
  int64_t gated = 0;

  FilterRun(const SimulationOptions& o, double t, const inertial::NavState& x0) : f(eskf_options(o)) {
    inertial::EskfState x;
    x.p = x0.p, x.v = x0.v, x.q = Eigen::Quaterniond(x0.R);
    inertial::ErrorStateEkf::Matrix15 P0 = inertial::ErrorStateEkf::Matrix15::Zero();
    P0.diagonal() << Eigen::Vector3d::Constant(0.25), Eigen::Vector3d::Constant(0.01), Eigen::Vector3d::Constant(1e-4),
        Eigen::Vector3d::Constant(0.05 * 0.05), Eigen::Vector3d::Constant(0.005 * 0.005);
    f.initialize(t, x, P0);
  }
  static inertial::EskfOptions eskf_options(const SimulationOptions& o) {
    inertial::EskfOptions eo;
    eo.noise = o.imu.noise;
    return eo;
  }
  void odometry(const odometry_t& m) {
    if (previous) {
      const double dt = static_cast<double>(m.utime - previous->utime) * 1e-6;
      const SE3 a = to_se3(previous->position, previous->orientation), b = to_se3(m.position, m.orientation);
      const Eigen::Vector3d v = (a.inverse() * b).translation() / dt;
      const Eigen::Map<const Eigen::Matrix<double, 6, 6, Eigen::RowMajor>> q(m.increment_covariance);
      const Eigen::Matrix3d R = q.topLeftCorner<3, 3>() / (dt * dt) + Eigen::Matrix3d::Identity() * 1e-4;
      f.propagate_to(static_cast<double>(m.utime) * 1e-6);
      f.update_body_velocity(v, R, inertial::SensorMounting{});
    }
    previous = m;
  }
  void gnss(double t, const Eigen::Vector3d& enu, const gnss_t& m, const Eigen::Vector3d& lever) {
    f.propagate_to(t);
    const auto u = f.update_gnss_position(enu, Eigen::Map<const Eigen::Matrix3d>(m.position_covariance), lever,
                                          inertial::kAllFields, 16.27);
    if (!u.accepted) ++gated;
    f.update_gnss_velocity(Eigen::Vector3d(m.velocity), Eigen::Map<const Eigen::Matrix3d>(m.velocity_covariance),
                           lever);
  }
};

struct Runs {
  Runs(const SimulationOptions& s, const InertialComparisonOptions& o, const std::map<int64_t, engine::Pose>& t)
      : sim(s), options(o), truth(t), plane(s.gnss.datum) {}
  const SimulationOptions& sim;
  const InertialComparisonOptions& options;
  const std::map<int64_t, engine::Pose>& truth;
  geodesy::LocalTangentPlane plane;
  std::optional<FilterRun> filter;
  std::optional<inertial::InertialSmoother> smoother;
  std::optional<SE3> first_odometry;
  SE3 truth_start;
  Scorer odometry_score, filter_score, smoother_score;
  double filter_seconds = 0, smoother_seconds = 0;
  std::vector<double> keyframe_cost;
  std::vector<double> filter_nees;

  void start(const odometry_t& m);
  void on_odometry(const odometry_t& m);
  void on_imu(const imu_t& m);
  void on_gnss(const gnss_t& m);
};

void Runs::start(const odometry_t& m) {
  const double t = static_cast<double>(m.utime) * 1e-6;
  const engine::Pose& p = truth.at(m.utime);
  const engine::Pose& next = truth.upper_bound(m.utime)->second;
  inertial::NavState x;
  x.R = p.orientation.toRotationMatrix();
  x.p = p.position;
  x.v = (next.position - p.position) * sim.odometry_rate_hz;
  filter.emplace(sim, t, x);
  inertial::InertialSmootherOptions so;
  so.noise = sim.imu.noise;
  so.gnss_lever_arm = sim.gnss.lever_arm;
  so.window = options.smoother_window;
  so.keyframe_interval = options.keyframe_interval;
  smoother.emplace(so);
  first_odometry = to_se3(m.position, m.orientation);
  smoother->initialize(t, x, {}, first_odometry);
  filter->previous = m;
  truth_start = SE3(SO3::from_unit_quaternion(p.orientation), p.position);
}

void Runs::on_odometry(const odometry_t& m) {
  if (!first_odometry) return start(m);
  const double t = static_cast<double>(m.utime) * 1e-6;
  const SE3 pose = to_se3(m.position, m.orientation);
  auto clock = Clock::now();
  filter->odometry(m);
  filter_seconds += seconds_since(clock);
  clock = Clock::now();
  const int64_t keyframes = smoother->counters().keyframes;
  const Eigen::Map<const Eigen::Matrix<double, 6, 6, Eigen::RowMajor>> q(m.increment_covariance);
  smoother->add_odometry(t, pose, floor_eigenvalues(Matrix6d(q), 1e-10));
  const double cost = seconds_since(clock);
  smoother_seconds += cost;
  if (smoother->counters().keyframes != keyframes) keyframe_cost.push_back(cost);

  const double since = t - static_cast<double>(sim.start_utime) * 1e-6;
  if (since < 10) return;
  const double phase = std::fmod(since, options.outage_period_s);
  const bool outage = phase >= options.outage_period_s - options.outage_duration_s;
  const bool settled = since > 20 && phase > 5;
  const Eigen::Vector3d p = truth.at(m.utime).position;
  odometry_score.add((truth_start * first_odometry->inverse() * pose).translation() - p, outage, settled);
  filter_score.add(filter->f.state().p - p, outage, settled);
  filter_nees.push_back(pose_nees(filter->f, truth.at(m.utime)));
  smoother_score.add(smoother->current().p - p, outage, settled);
}

void Runs::on_imu(const imu_t& m) {
  const double t = static_cast<double>(m.utime) * 1e-6;
  const inertial::BodyImuSample s = inertial::imu_to_body(sim.imu.mounting, Eigen::Vector3d(m.angular_velocity),
                                                          Eigen::Vector3d(m.linear_acceleration));
  auto clock = Clock::now();
  filter->f.add_imu(t, s);
  filter_seconds += seconds_since(clock);
  clock = Clock::now();
  smoother->add_imu(t, s);
  smoother_seconds += seconds_since(clock);
}

void Runs::on_gnss(const gnss_t& m) {
  const double t = static_cast<double>(m.utime) * 1e-6;
  const Eigen::Vector3d enu = plane.to_enu({m.latitude, m.longitude, m.altitude});
  auto clock = Clock::now();
  filter->gnss(t, enu, m, sim.gnss.lever_arm);
  filter_seconds += seconds_since(clock);
  clock = Clock::now();
  smoother->add_gnss(t, enu, Eigen::Map<const Eigen::Matrix3d>(m.position_covariance));
  smoother_seconds += seconds_since(clock);
}

}  // namespace

InertialComparison compare_inertial(const InertialComparisonOptions& options) {
  const SimulationOptions sim = simulation_options(options);
  SimulationSummary summary;
  const std::vector<runtime::LogRecord> records = simulate_records(sim, summary);
  const std::map<int64_t, engine::Pose> truth(summary.robot_truth.begin(), summary.robot_truth.end());
  Runs runs(sim, options, truth);
  for (const auto& r : records) {
    if (r.channel == "ODOMETRY") {
      odometry_t m;
      if (runtime::decode_message(r.data, m)) runs.on_odometry(m);
    } else if (r.channel == "IMU" && runs.first_odometry) {
      imu_t m;
      if (runtime::decode_message(r.data, m)) runs.on_imu(m);
    } else if (r.channel == "GNSS" && runs.first_odometry) {
      gnss_t m;
      if (runtime::decode_message(r.data, m)) runs.on_gnss(m);
    }
  }
  InertialComparison c;
  c.odometry = runs.odometry_score.score();
  c.filter = runs.filter_score.score();
  c.smoother = runs.smoother_score.score();
  c.gnss_fixes = summary.gnss;
  c.gnss_outliers = summary.gnss_outliers;
  c.filter_gated = runs.filter->gated;
  c.smoother_down_weighted = runs.smoother->counters().gnss_down_weighted;
  c.filter_nees = std::move(runs.filter_nees);
  c.filter_seconds = runs.filter_seconds;
  c.smoother_seconds = runs.smoother_seconds;
  const auto& k = runs.keyframe_cost;
  const size_t n = std::min<size_t>(200, k.size());
  c.keyframe_cost_first = median(std::vector<double>(k.begin(), k.begin() + static_cast<long>(n)));
  c.keyframe_cost_last = median(std::vector<double>(k.end() - static_cast<long>(n), k.end()));
  c.keyframes = runs.smoother->counters().keyframes;
  return c;
}

}  // namespace sextant::tools
