#pragma once
// Planar robots on circles with exact odometry and range/bearing sightings, for the SLAM layer's fleet tests.
#include "estimators/lie/se2.hpp"
#include "estimators/slam/slam_graph.hpp"

#include <cmath>
#include <map>
#include <random>
#include <string>

namespace sextant::slam::test {

struct Quiet final : SlamListener {
  void updated(const std::string&, int64_t, const graph::IncrementalStatus&) override {}
  void loop_proposed(const std::string&, int64_t, const KeyframeEstimate&, const KeyframeEstimate&, bool) override {}
};

/// A planar robot driving a circle of `radius` about `centre`, starting at angle `phase`, `turn` rad per second.
struct Robot {
  std::string name;
  Eigen::Vector2d centre;
  double radius = 3, phase = 0, turn = 0.3;
  SE2 truth(double t) const {
    const double a = phase + turn * t;
    return SE2(centre.x() + radius * std::cos(a), centre.y() + radius * std::sin(a),
               a + (turn > 0 ? M_PI / 2 : -M_PI / 2));
  }
  /// The odometry pose: the truth in the robot's own frame (identity at t = 0).
  SE3 odometry(double t) const { return (truth(0).inverse() * truth(t)).to_se3(); }
};

inline OdometryInput odometry_at(const Robot& r, double t) {
  OdometryInput o;
  o.utime = static_cast<int64_t>(std::llround(t * 1e6)) + 1000000;
  o.planar = true;
  o.pose = r.odometry(t);
  Matrix6d q = Matrix6d::Zero();
  q(0, 0) = q(1, 1) = 1e-6, q(5, 5) = 1e-7;
  o.increment_covariance = q;
  o.covariance = q * (t * 10 + 1);
  return o;
}

/// Exact range/bearing sightings of every point within 5 m (ids: the map's keys).
inline SightingsInput sightings_at(const Robot& r, double t, const std::map<int64_t, Eigen::Vector2d>& points) {
  SightingsInput s;
  s.utime = static_cast<int64_t>(std::llround(t * 1e6)) + 1000000;
  s.planar = true;
  const SE2 x = r.truth(t);
  for (const auto& [id, p] : points) {
    const Eigen::Vector2d l = x.inverse().act(p);
    if (l.norm() > 5 || l.norm() < 0.1) continue;
    LandmarkSighting o;
    o.id = id;
    o.range = l.norm();
    o.azimuth = std::atan2(l.y(), l.x());
    o.covariance = Eigen::Vector3d(1e-4, 2.5e-5, 1).asDiagonal();
    s.sightings.push_back(o);
  }
  return s;
}

inline std::map<int64_t, Eigen::Vector2d> random_landmarks(uint32_t seed, int n) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-5, 5);
  std::map<int64_t, Eigen::Vector2d> out;
  for (int k = 0; k < n; ++k) out[k] = {u(rng), u(rng)};
  return out;
}

}  // namespace sextant::slam::test
