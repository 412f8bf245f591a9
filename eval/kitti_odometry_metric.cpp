#include "eval/kitti_odometry_metric.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace sextant::tools {
namespace {

Eigen::Isometry3d isometry(const engine::Pose& p) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = p.orientation.normalized().toRotationMatrix();
  T.translation() = p.position;
  return T;
}

}  // namespace

KittiOdometryError kitti_odometry_error(const std::vector<engine::Pose>& gt, const std::vector<engine::Pose>& est,
                                        const KittiMetricOptions& options) {
  if (gt.size() != est.size())
    throw std::invalid_argument("KITTI error: " + std::to_string(est.size()) + " estimated poses for " +
                                std::to_string(gt.size()) + " ground-truth poses (they are compared frame by frame)");
  if (options.lengths.empty() || options.step == 0)
    throw std::invalid_argument("KITTI error: needs at least one segment length and a step of at least one frame");
  for (double L : options.lengths)
    if (!(L > 0))
      throw std::invalid_argument("KITTI error: segment length " + std::to_string(L) + " m is not positive");

  if (gt.size() < 2) throw std::invalid_argument("KITTI error: needs at least two poses");
  std::vector<double> distance(gt.size(), 0.0);
  for (size_t i = 1; i < gt.size(); ++i) distance[i] = distance[i - 1] + (gt[i].position - gt[i - 1].position).norm();

  KittiOdometryError out;
  for (size_t first = 0; first < gt.size(); first += options.step) {
    for (double L : options.lengths) {
      // The first frame whose path distance exceeds the start's by more than L (distance is non-decreasing).
      const auto it =
          std::upper_bound(distance.begin() + static_cast<std::ptrdiff_t>(first), distance.end(), distance[first] + L);
      if (it == distance.end()) continue;
      const size_t last = static_cast<size_t>(it - distance.begin());
      const Eigen::Isometry3d delta_gt = isometry(gt[first]).inverse() * isometry(gt[last]);
      const Eigen::Isometry3d delta_est = isometry(est[first]).inverse() * isometry(est[last]);
      const Eigen::Isometry3d E = delta_est.inverse() * delta_gt;
      const double c = std::clamp((E.linear().trace() - 1.0) / 2.0, -1.0, 1.0);
      out.segments.push_back({first, L, E.translation().norm() / L, std::acos(c) / L});
    }
  }
  if (out.segments.empty())
    throw std::invalid_argument("KITTI error: the ground truth travels " + std::to_string(distance.back()) +
                                " m, shorter than the shortest segment length");
  double t = 0, r = 0;
  for (const auto& s : out.segments) {
    t += s.translation;
    r += s.rotation;
  }
  const double n = static_cast<double>(out.segments.size());
  out.translation_percent = 100.0 * t / n;
  out.rotation_deg_per_m = (r / n) * 180.0 / M_PI;
  return out;
}

}  // namespace sextant::tools
