#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace sextant::engine {

/// The online filter: a planar EKF per odometry source, fusing odometry increments and range-bearing landmark
/// sightings (localization against `map`, EKF-SLAM for landmarks not in it).
struct FilterConfig {
  std::string type = "ekf";  // "ekf" or "none"
  bool slam = true;          // add landmarks that are not in `map` to the state
  double gate = 9.21;        // chi-square threshold (2 dof) on the normalized innovation; 9.21 = 99 %
  double initial_sigma_xy = 0.01;     // m, first pose (the first odometry pose anchors the map frame)
  double initial_sigma_theta = 0.01;  // rad
  double min_increment_variance = 1e-10;
  int max_landmarks = 4096;
  struct Landmark {
    int64_t id = 0;
    double x = 0, y = 0;
  };
  std::vector<Landmark> map;  // known landmarks (map frame)
};

}  // namespace sextant::engine
