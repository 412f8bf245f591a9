#pragma once
// Planar robots on circles with exact odometry and range/bearing sightings, for the SLAM layer's fleet tests.
#include "estimators/lie/se2.hpp"
#include "estimators/slam/slam_graph.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <map>
#include <random>
#include <string>
#include <vector>

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

/// Exact range/bearing sightings of every point within `max_range` metres (ids: the map's keys).
inline SightingsInput sightings_at(const Robot& r, double t, const std::map<int64_t, Eigen::Vector2d>& points,
                                   double max_range = 5) {
  SightingsInput s;
  s.utime = static_cast<int64_t>(std::llround(t * 1e6)) + 1000000;
  s.planar = true;
  const SE2 x = r.truth(t);
  for (const auto& [id, p] : points) {
    const Eigen::Vector2d l = x.inverse().act(p);
    if (l.norm() > max_range || l.norm() < 0.1) continue;
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

/// Three robots a, b, c on circles about the origin, each a marker of the others (ids 1001, 1000, 1002).
inline SlamOptions three_robot_options() {
  SlamOptions o;
  o.propose_loops = false;
  o.fleet.markers = {{1000, "b"}, {1001, "a"}, {1002, "c"}};
  return o;
}

inline const Robot kThreeRobots[] = {
    {"a", {0, 0}, 3, 0, 0.3}, {"b", {0.5, 0.5}, 2.5, 2.0, -0.25}, {"c", {-0.5, 0.2}, 2.8, 4.0, 0.2}};

/// Robot k's inputs at step i (10 Hz odometry, 5 Hz sightings of the shared landmarks and of the other robots), and
/// at step 60 an inter-robot loop from a (at 4 s) to c (at 4.5 s).
inline void feed_three_robots(SlamGraph& g, int k, int i, const std::map<int64_t, Eigen::Vector2d>& world,
                              SlamListener& out) {
  const Robot& r = kThreeRobots[k];
  const double t = 0.1 * i;
  g.add_odometry(r.name, odometry_at(r, t), out);
  if (i % 2 == 0) {
    auto points = world;
    for (int j = 0; j < 3; ++j)
      if (j != k) points[1000 + (j == 0 ? 1 : j == 1 ? 0 : 2)] = kThreeRobots[j].truth(t).translation();
    g.add_sightings(r.name, sightings_at(r, t, points), out);
  }
  if (k == 0 && i == 60) {
    LoopInput l;
    l.utime_from = 5000000, l.utime_to = 5500000;
    l.relative = (kThreeRobots[0].truth(4).inverse() * kThreeRobots[2].truth(4.5)).to_se3();
    l.information = Matrix6d::Identity() * 1e4;
    l.body_to = kThreeRobots[2].name;
    g.add_loop("a", l, out);
  }
}

/// RMS distance between two estimates of the same keyframes (checked: the same ids, in order).
inline double rms_between(const std::vector<KeyframeEstimate>& x, const std::vector<KeyframeEstimate>& y) {
  REQUIRE(x.size() == y.size());
  double sum = 0;
  for (size_t k = 0; k < x.size(); ++k) {
    CHECK(x[k].id == y[k].id);
    sum += (x[k].pose.translation() - y[k].pose.translation()).squaredNorm();
  }
  return std::sqrt(sum / static_cast<double>(x.size()));
}

}  // namespace sextant::slam::test
