#include "sim/simulator.hpp"

#include "assoc/field_of_view.hpp"
#include "daemon/engine/dead_reckoning_stage.hpp"
#include "daemon/runtime/codec.hpp"
#include "estimators/kind_names.hpp"
#include "estimators/lie/planar_axes.hpp"

#include <sextant/truth_t.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <span>
#include <stdexcept>
#include <utility>

namespace sextant::tools {
namespace {

constexpr double kPi = 3.14159265358979323846;
using Matrix6 = engine::Matrix6;
using Vector6 = Eigen::Matrix<double, 6, 1>;

// The stadium course: straight sides of length 2*half_straight along x at y = +-radius, joined by half circles.
struct Course {
  double half_straight = 10, radius = 8;
  double perimeter() const { return 4 * half_straight + 2 * kPi * radius; }

  // Planar position and heading at arc length s (counter-clockwise, starting at (-half_straight, -radius)).
  void at(double s, double& x, double& y, double& yaw) const {
    s = std::fmod(s, perimeter());
    if (s < 0) s += perimeter();
    const double L = 2 * half_straight, arc = kPi * radius;
    if (s < L) {
      x = -half_straight + s, y = -radius, yaw = 0;
    } else if (s < L + arc) {
      const double a = (s - L) / radius;  // 0..pi around (half_straight, 0)
      x = half_straight + radius * std::sin(a), y = -radius * std::cos(a), yaw = a;
    } else if (s < 2 * L + arc) {
      x = half_straight - (s - L - arc), y = radius, yaw = kPi;
    } else {
      const double a = (s - 2 * L - arc) / radius;
      x = -half_straight - radius * std::sin(a), y = radius * std::cos(a), yaw = kPi + a;
    }
  }
};

Eigen::Isometry3d make_iso(const Eigen::Vector3d& t, const Eigen::Quaterniond& q) {
  Eigen::Isometry3d x = Eigen::Isometry3d::Identity();
  x.linear() = q.toRotationMatrix();
  x.translation() = t;
  return x;
}

engine::Pose to_pose(const Eigen::Isometry3d& x) {
  engine::Pose p;
  p.position = x.translation();
  p.orientation = Eigen::Quaterniond(x.linear()).normalized();
  return p;
}

// Exp(xi) as an isometry: noise is injected on the right, as the covariances the messages carry assume.
Eigen::Isometry3d perturbation(const Vector6& xi) { return SE3::exp(xi).isometry(); }

SE3 to_se3(const Eigen::Isometry3d& x) { return SE3(Eigen::Quaterniond(x.linear()), x.translation()); }

struct HistoryEntry {
  int64_t utime;
  Eigen::Isometry3d pose;
};

// One robot of the run: its name, its course and its odometry.
struct Robot {
  std::string source;
  int64_t marker = 0;          // a fleet's: the id of its sightings by the others (and of its truth_t)
  double course_rotation = 0;  // its course, rotated about the origin, rad
  bool started = false;
  Eigen::Isometry3d odom = Eigen::Isometry3d::Identity(), last_truth = Eigen::Isometry3d::Identity();
  Matrix6 cov = Matrix6::Zero();  // the odometry's pose covariance
  std::vector<HistoryEntry> history;
  int64_t last_loop = 0, last_loop_check = 0, last_inter_loop = 0, last_inter_check = 0;
};

class Simulation {
 public:
  Simulation(const SimulationOptions& o, runtime::LogWriter& out) : o_(o), out_(out), rng_(o.seed) {
    if (!(o.duration_s > 0) || !(o.speed > 0) || !(o.odometry_rate_hz > 0) || !(o.landmark_rate_hz > 0) ||
        !(o.scan_rate_hz > 0))
      throw std::invalid_argument("duration, speed and rates must be positive");
    if (o.sensors < 2) throw std::invalid_argument("at least 2 passive sensors");
    if (o.p_detect < 0 || o.p_detect > 1 || o.clutter < 0) throw std::invalid_argument("bad p_detect or clutter");
    if (o.clutter_region_min.size() != o.clutter_region_max.size() ||
        (!o.clutter_region_min.empty() && o.clutter_region_min.size() != 3))
      throw std::invalid_argument("clutter region: min and max need 3 numbers each (x, y, z), or neither");
    for (size_t i = 0; i < o.clutter_region_min.size(); ++i)
      if (!(o.clutter_region_min[i] < o.clutter_region_max[i]))
        throw std::invalid_argument("clutter region: min must be below max on every axis (axis " + std::to_string(i) +
                                    ")");
    if (o.imu_rate_hz < 0 || o.gnss_rate_hz < 0) throw std::invalid_argument("IMU and GNSS rates must not be negative");
    if (o.robots < 1 || o.robots > 1000) throw std::invalid_argument("robots: 1 to 1000");
    if (!(o.wrong_loops >= 0 && o.wrong_loops <= 1)) throw std::invalid_argument("wrong loops: a share, 0 to 1");
    if (o.landmarks >= fleet_marker(0)) throw std::invalid_argument("landmark ids must stay below the markers");
    planar_ = o.scenario == Scenario::kPlanar;
    fleet_ = o.robots > 1;
    if (fleet_ && (o.imu_rate_hz > 0 || o.gnss_rate_hz > 0))
      throw std::invalid_argument("IMU and GNSS are simulated for one robot only");
    for (int i = 0; i < o.robots; ++i) {
      Robot r;
      r.source = fleet_ ? "robot" + std::to_string(i + 1) : o.source;
      r.marker = fleet_ ? fleet_marker(i + 1) : 0;
      r.course_rotation = kPi * i / o.robots;
      robots_.push_back(std::move(r));
      if (fleet_) summary_.markers[robots_.back().marker] = robots_.back().source;
    }
    if (o.imu_rate_hz > 0 || o.gnss_rate_hz > 0) {
      imu_ = o.imu, gnss_ = o.gnss;
      imu_.rate_hz = o.imu_rate_hz, gnss_.rate_hz = o.gnss_rate_hz;
      inertial_.emplace([this](double t) { return truth_at(robots_.front(), t); }, imu_, gnss_, o.seed ^ 0x1e27ULL);
    }
  }

  SimulationSummary run() {
    place_world();
    const int64_t t0 = o_.start_utime;
    const int64_t end = t0 + static_cast<int64_t>(o_.duration_s * 1e6);
    const auto period = [](double hz) { return static_cast<int64_t>(std::llround(1e6 / hz)); };
    // Event times of every stream, merged in time order (ties: truth, odometry, landmarks, scans, loops).
    int64_t next_odo = t0, next_lm = t0 + period(o_.landmark_rate_hz) / 2, next_scan = t0 + period(o_.scan_rate_hz) / 3;
    const int64_t never = std::numeric_limits<int64_t>::max();
    int64_t next_imu = o_.imu_rate_hz > 0 ? t0 : never, next_gnss = o_.gnss_rate_hz > 0 ? t0 : never;
    write_landmark_truth(t0);
    while (true) {
      const int64_t t = std::min({next_odo, next_lm, next_scan, next_imu, next_gnss});
      if (t > end) break;
      if (t == next_odo) {
        for (auto& r : robots_) odometry_step(r, t);
        if (fleet_)
          for (auto& r : robots_) consider_inter_robot_loop(r, t);
        next_odo += period(o_.odometry_rate_hz);
      }
      if (t == next_lm) {
        for (const auto& r : robots_) landmark_step(r, t);
        next_lm += period(o_.landmark_rate_hz);
      }
      if (t == next_scan) {
        scan_step(t);
        next_scan += period(o_.scan_rate_hz);
      }
      if (t == next_imu) {
        imu_step(t);
        next_imu += period(o_.imu_rate_hz);
      }
      if (t == next_gnss) {
        gnss_step(t);
        next_gnss += period(o_.gnss_rate_hz);
      }
    }
    return summary_;
  }

 private:
  double gauss(double sigma) { return std::normal_distribution<double>(0.0, sigma)(rng_); }
  double uniform(double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng_); }

  // True pose of robot r at time t.
  Eigen::Isometry3d truth(const Robot& r, int64_t utime) const {
    return truth_at(r, static_cast<double>(utime - o_.start_utime) * 1e-6);
  }
  // ... at t seconds after the start: on the course, rotated by the robot's course rotation about the origin.
  Eigen::Isometry3d truth_at(const Robot& r, double t) const {
    const Eigen::Isometry3d x = course_pose(t);
    if (r.course_rotation == 0) return x;
    return Eigen::Isometry3d(Eigen::AngleAxisd(r.course_rotation, Eigen::Vector3d::UnitZ())) * x;
  }
  Eigen::Isometry3d course_pose(double t) const {
    const double s = o_.speed * t;
    double x, y, yaw;
    course_.at(s, x, y, yaw);
    double z = 0, pitch = 0, roll = 0;
    if (!planar_) {
      const double w = 2 * kPi * 2 / course_.perimeter();  // two hills per lap
      z = 2.0 + 1.0 * std::sin(w * s);
      pitch = -std::atan(1.0 * w * std::cos(w * s));  // nose up when climbing (z-up, x-forward: negative pitch)
      roll = 0.05 * std::sin(3 * w * s);
    }
    const Eigen::Quaterniond q = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                                 Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX());
    return make_iso({x, y, z}, q);
  }

  Eigen::Vector3d target_position(int i, int64_t utime) const {
    const auto& tg = targets_[static_cast<size_t>(i)];
    const double t = static_cast<double>(utime - o_.start_utime) * 1e-6;
    const double a = tg.phase + tg.omega * t;
    return tg.centre + Eigen::Vector3d(tg.radius * std::cos(a), tg.radius * std::sin(a), 0.5 * std::sin(0.3 * a));
  }

  void place_world() {
    // The rotated courses of a fleet reach 18 m from the origin in every direction.
    const double x_max = fleet_ ? 24 : 28, y_max = fleet_ ? 24 : 16;
    for (int i = 0; i < o_.landmarks; ++i) {
      landmarks_.push_back({uniform(-x_max, x_max), uniform(-y_max, y_max), planar_ ? 0.0 : uniform(0, 4)});
      summary_.landmarks[i] = landmarks_.back();
    }
    // Passive sensors around the area, at different heights (elevation geometry needs them).
    const double ring = 40;
    for (int i = 0; i < o_.sensors; ++i) {
      const double a = 2 * kPi * i / o_.sensors + 0.3;
      sensors_.push_back({ring * std::cos(a), ring * 0.7 * std::sin(a), 0.5 + 1.5 * (i % 3)});
      if (!o_.clutter_region_min.empty()) {
        const Eigen::Vector3d lo(o_.clutter_region_min.data()), hi(o_.clutter_region_max.data());
        clutter_view_.push_back(assoc::field_of_view(sensors_.back(), lo, hi, 5 * o_.bearing_sensor_sigma));
      }
    }
    for (int i = 0; i < o_.targets; ++i)
      targets_.push_back({Eigen::Vector3d(uniform(-20, 20), uniform(-12, 12), uniform(5, 15)), uniform(2, 6),
                          uniform(0.05, 0.15) * (i % 2 ? 1 : -1), uniform(0, 2 * kPi)});
  }

  void write_truth(int64_t utime, const std::string& kind, int64_t id, const Eigen::Vector3d& p,
                   const Eigen::Quaterniond& q = Eigen::Quaterniond::Identity(), const std::string& source = "") {
    sextant::truth_t m{};
    m.utime = utime;
    m.sender = kSender;
    m.seq = seq_["GROUND_TRUTH"]++;
    m.kind = kind;
    m.source = source;
    m.id = id;
    for (int i = 0; i < 3; ++i) m.position[i] = p[i];
    m.orientation[0] = q.w(), m.orientation[1] = q.x(), m.orientation[2] = q.y(), m.orientation[3] = q.z();
    out_.write(utime, "GROUND_TRUTH", m);
    ++summary_.truth;
  }

  double seconds(int64_t utime) const { return static_cast<double>(utime - o_.start_utime) * 1e-6; }

  void imu_step(int64_t t) {
    const ImuReading r = inertial_->imu(seconds(t));
    out_.write(t, "IMU", InertialSensorSimulator::to_message(r, imu_, t, o_.source, seq_["IMU"]++));
    ++summary_.imu;
  }

  void gnss_step(int64_t t) {
    const auto r = inertial_->gnss(seconds(t));
    if (!r) return;  // an outage
    out_.write(t, "GNSS", InertialSensorSimulator::to_message(*r, gnss_, t, o_.source, seq_["GNSS"]++));
    ++summary_.gnss;
    summary_.gnss_outliers += r->outlier;
  }

  void write_landmark_truth(int64_t utime) {
    for (size_t i = 0; i < landmarks_.size(); ++i)
      write_truth(utime, "landmark", static_cast<int64_t>(i), landmarks_[i]);
  }

  void odometry_step(Robot& r, int64_t t) {
    const Eigen::Isometry3d T = truth(r, t);
    write_truth(t, "robot", r.marker, T.translation(), Eigen::Quaterniond(T.linear()), r.source);
    if (&r == &robots_.front()) summary_.robot_truth.push_back({t, to_pose(T)});
    if (fleet_) summary_.fleet_truth[r.source].push_back({t, to_pose(T)});

    engine::Odometry odo;
    odo.utime = t;
    odo.source = r.source;
    odo.planar = planar_;
    if (!r.started) {
      r.started = true;
      // One robot: the odometry frame coincides with the world at the start; a fleet's robots start in their own.
      r.odom = fleet_ ? Eigen::Isometry3d::Identity() : T;
      r.cov = Matrix6::Zero();
      for (int i : active()) r.cov(i, i) = 1e-6;
      odo.increment_covariance = Matrix6::Zero();
      for (int i : active()) (*odo.increment_covariance)(i, i) = 1e-6;
    } else {
      const Eigen::Isometry3d delta_true = r.last_truth.inverse() * T;
      const double dist = delta_true.translation().norm();
      Matrix6 q = Matrix6::Zero();
      Vector6 eta = Vector6::Zero();
      for (int i : active()) {
        const double sigma =
            std::max(o_.odometry_min_sigma, (i < 3 ? o_.odometry_trans_noise : o_.odometry_rot_noise) * dist);
        q(i, i) = sigma * sigma;
        eta[i] = gauss(sigma);
      }
      const Eigen::Isometry3d delta = delta_true * perturbation(eta);
      r.cov = engine::DeadReckoningStage::propagate(r.cov, to_se3(delta), q);
      r.odom = r.odom * delta;
      odo.increment_covariance = q;
      consider_loop(r, t, T);
    }
    odo.pose = to_pose(r.odom);
    odo.covariance = r.cov;
    out_.write(t, "ODOMETRY", runtime::to_message(odo, kSender, seq_["ODOMETRY"]++));
    ++summary_.odometry;
    r.last_truth = T;
    r.history.push_back({t, T});
    if (fleet_) visits_[cell_of(T.translation())][&r - robots_.data()] = {t, T};
  }

  std::span<const int> active() const { return pose_axes(planar_); }

  // A noisy range/azimuth(/elevation) sighting of world point `w` from pose T, or nothing outside range and view.
  std::optional<engine::LandmarkObservation> sighting(const Eigen::Isometry3d& T, const Eigen::Vector3d& w,
                                                      int64_t id) {
    const Eigen::Vector3d p = T.inverse() * w;
    const double range = planar_ ? std::hypot(p.x(), p.y()) : p.norm();
    const double az = std::atan2(p.y(), p.x());
    if (range > o_.landmark_max_range || range < 0.5 || std::abs(az) > o_.landmark_fov / 2) return std::nullopt;
    engine::LandmarkObservation ob;
    ob.id = o_.unknown_ids ? -1 : id;
    ob.range = range + gauss(o_.range_sigma);
    ob.azimuth = az + gauss(o_.bearing_sigma);
    ob.elevation = planar_ ? 0.0 : std::atan2(p.z(), std::hypot(p.x(), p.y())) + gauss(o_.bearing_sigma);
    ob.covariance = Eigen::Vector3d(o_.range_sigma * o_.range_sigma, o_.bearing_sigma * o_.bearing_sigma,
                                    planar_ ? 0.0 : o_.bearing_sigma * o_.bearing_sigma)
                        .asDiagonal();
    return ob;
  }

  // The landmarks, and in a fleet the other robots' origins (by their markers), that robot r sees at t.
  void landmark_step(const Robot& r, int64_t t) {
    const Eigen::Isometry3d T = truth(r, t);
    engine::LandmarkSightings s;
    s.utime = t;
    s.source = r.source;
    s.planar = planar_;
    for (size_t i = 0; i < landmarks_.size(); ++i)
      if (auto ob = sighting(T, landmarks_[i], static_cast<int64_t>(i))) s.observations.push_back(*ob);
    summary_.landmark_observations += static_cast<int64_t>(s.observations.size());
    for (const auto& other : robots_) {
      if (&other == &r) continue;
      if (auto ob = sighting(T, truth(other, t).translation(), other.marker)) {
        s.observations.push_back(*ob);
        ++summary_.robot_sightings;
      }
    }
    ++summary_.landmark_messages;
    out_.write(t, "LANDMARKS", runtime::to_message(s, kSender, seq_["LANDMARKS"]++));
  }

  void scan_step(int64_t t) {
    for (int i = 0; i < o_.targets; ++i) write_truth(t, "target", i, target_position(i, t));
    for (int si = 0; si < o_.sensors; ++si) {
      const Eigen::Vector3d& sp = sensors_[static_cast<size_t>(si)];
      engine::BearingScan scan;
      scan.utime = t;
      scan.sensor_id = si + 1;
      scan.sensor_position = sp;
      scan.scan_id = scan_id_;
      const double sg = o_.bearing_sensor_sigma;
      for (int i = 0; i < o_.targets; ++i) {
        if (uniform(0, 1) >= o_.p_detect) continue;
        const Eigen::Vector3d d = target_position(i, t) - sp;
        scan.detections.push_back(
            {std::atan2(d.y(), d.x()) + gauss(sg), std::atan(d.z() / std::hypot(d.x(), d.y())) + gauss(sg), sg, sg});
        ++summary_.detections;
      }
      const int n_false = std::poisson_distribution<int>(o_.clutter)(rng_);
      for (int k = 0; k < n_false; ++k) {
        if (clutter_view_.empty()) {
          scan.detections.push_back({uniform(-kPi, kPi), uniform(0.0, 0.8), sg, sg});
        } else {
          const auto& f = clutter_view_[static_cast<size_t>(si)];
          const double az = std::remainder(f.centre_azimuth + uniform(f.azimuth_lo, f.azimuth_hi), 2 * kPi);
          scan.detections.push_back({az, uniform(f.elevation_lo, f.elevation_hi), sg, sg});
        }
        ++summary_.false_alarms;
      }
      std::shuffle(scan.detections.begin(), scan.detections.end(), rng_);
      out_.write(t, "BEARINGS", runtime::to_message(scan, kSender, seq_["BEARINGS"]++));
      ++summary_.bearing_scans;
    }
    ++scan_id_;
  }

  // The loop's noise: a right perturbation with the loops' sigmas, and the matching information.
  std::pair<Eigen::Isometry3d, Matrix6> loop_noise() {
    Vector6 eta = Vector6::Zero();
    Matrix6 info = Matrix6::Zero();
    for (int i : active()) {
      const double sigma = i < 3 ? o_.loop_trans_sigma : o_.loop_rot_sigma;
      eta[i] = gauss(sigma);
      info(i, i) = 1.0 / (sigma * sigma);
    }
    return {perturbation(eta), info};
  }

  void write_loop(int64_t t, const std::string& from, const std::string& to, int64_t utime_from,
                  const Eigen::Isometry3d& relative, const Matrix6& info) {
    engine::LoopClosure lc;
    lc.utime = t;
    lc.source = from;
    lc.source_to = to == from ? "" : to;
    lc.planar = planar_;
    lc.utime_from = utime_from;
    lc.utime_to = t;
    lc.relative = to_pose(relative);
    lc.information = info;
    lc.matcher = "sextant-sim";
    lc.score = 1.0;
    out_.write(t, "LOOP_CLOSURES", runtime::to_message(lc, kSender, seq_["LOOP_CLOSURES"]++));
    ++summary_.loop_closures;
  }

  void consider_loop(Robot& r, int64_t t, const Eigen::Isometry3d& T) {
    if (t - r.last_loop < static_cast<int64_t>(o_.loop_min_interval_s * 1e6)) return;
    if (t - r.last_loop_check < 200'000) return;  // look for revisits at 5 Hz: the history scan is linear
    r.last_loop_check = t;
    const int64_t oldest_allowed = t - static_cast<int64_t>(o_.loop_min_age_s * 1e6);
    const HistoryEntry* best = nullptr;
    double best_d = o_.loop_distance;
    for (const auto& h : r.history) {
      if (h.utime > oldest_allowed) break;
      const double d = (h.pose.translation() - T.translation()).norm();
      if (d < best_d) best_d = d, best = &h;
    }
    if (best == nullptr) return;
    const auto [noise, info] = loop_noise();
    write_loop(t, r.source, r.source, best->utime, best->pose.inverse() * T * noise, info);
    r.last_loop = t;
  }

  // The grid cell (loop_distance wide, in x and y) of a position.
  std::pair<int64_t, int64_t> cell_of(const Eigen::Vector3d& p) const {
    const double w = std::max(o_.loop_distance, 1e-3);
    return {static_cast<int64_t>(std::floor(p.x() / w)), static_cast<int64_t>(std::floor(p.y() / w))};
  }

  // A fleet's inter-robot loop: robot r now against the nearest latest visit of another robot nearby (a share of
  // them made wrong on purpose).
  void consider_inter_robot_loop(Robot& r, int64_t t) {
    if (!(o_.loop_distance > 0) || t - r.last_inter_loop < static_cast<int64_t>(o_.loop_min_interval_s * 1e6)) return;
    if (t - r.last_inter_check < 200'000) return;
    r.last_inter_check = t;
    const Eigen::Isometry3d T = r.last_truth;
    const auto [cx, cy] = cell_of(T.translation());
    const HistoryEntry* best = nullptr;
    size_t best_robot = 0;
    double best_d = o_.loop_distance;
    for (int64_t dx = -1; dx <= 1; ++dx)
      for (int64_t dy = -1; dy <= 1; ++dy) {
        const auto it = visits_.find({cx + dx, cy + dy});
        if (it == visits_.end()) continue;
        for (const auto& [robot, h] : it->second) {
          const double d = (h.pose.translation() - T.translation()).norm();
          if (&robots_[robot] != &r && d < best_d) best_d = d, best = &h, best_robot = robot;
        }
      }
    if (best == nullptr) return;
    auto [noise, info] = loop_noise();
    if (uniform(0, 1) < o_.wrong_loops) {
      const double a = uniform(-kPi, kPi), distance = uniform(3, 10);
      noise = noise * make_iso({distance * std::cos(a), distance * std::sin(a), 0},
                               Eigen::Quaterniond(Eigen::AngleAxisd(uniform(-kPi, kPi), Eigen::Vector3d::UnitZ())));
      ++summary_.wrong_loops;
      if (o_.omit_wrong_loops) {  // as if written and lost: the next loops come at the same times and numbers
        r.last_inter_loop = t;
        ++seq_["LOOP_CLOSURES"];
        return;
      }
    }
    write_loop(t, robots_[best_robot].source, r.source, best->utime, best->pose.inverse() * T * noise, info);
    ++summary_.inter_robot_loops;
    r.last_inter_loop = t;
  }

  static constexpr const char* kSender = "sextant-sim";
  struct Target {
    Eigen::Vector3d centre;
    double radius, omega, phase;
  };

  const SimulationOptions& o_;
  runtime::LogWriter& out_;
  std::mt19937_64 rng_;
  bool planar_ = true;
  Course course_;
  SimulatedImuOptions imu_;  // o_.imu and o_.gnss with their rates
  SimulatedGnssOptions gnss_;
  std::optional<InertialSensorSimulator> inertial_;
  std::vector<Eigen::Vector3d> landmarks_, sensors_;
  std::vector<Target> targets_;
  std::vector<assoc::FieldOfView> clutter_view_;  // per sensor, with a clutter region
  std::map<std::string, int64_t> seq_;
  bool fleet_ = false;
  std::vector<Robot> robots_;
  // A fleet's latest visit of each robot to each grid cell, by robot index: where inter-robot loops are looked for.
  std::map<std::pair<int64_t, int64_t>, std::map<size_t, HistoryEntry>> visits_;
  int64_t scan_id_ = 0;
  SimulationSummary summary_;
};

}  // namespace

namespace {
constexpr std::pair<Scenario, const char*> kScenarios[] = {{Scenario::kPlanar, "planar"},
                                                           {Scenario::kSpatial, "spatial"}};
}  // namespace

Scenario scenario_from_name(const std::string& name) { return kind_from_name(kScenarios, name, "scenario"); }
const char* scenario_name(Scenario scenario) { return kind_name(kScenarios, scenario); }
std::vector<std::string> scenario_names() { return kind_names(kScenarios); }

SimulationSummary simulate(const SimulationOptions& options, runtime::LogWriter& out) {
  return Simulation(options, out).run();
}

}  // namespace sextant::tools
