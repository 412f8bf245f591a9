#include "eval/fleet_eval.hpp"

#include <stdexcept>

namespace sextant::tools {
namespace {

// Corresponding points: the estimate's (model) and the ground truth's (data), columns in the same order.
struct Correspondences {
  std::vector<Eigen::Vector3d> model, data;
  Eigen::Matrix3Xd matrix(const std::vector<Eigen::Vector3d>& points) const {
    Eigen::Matrix3Xd m(3, static_cast<Eigen::Index>(points.size()));
    for (size_t k = 0; k < points.size(); ++k) m.col(static_cast<Eigen::Index>(k)) = points[k];
    return m;
  }
};

Correspondences matched_keyframes(const std::vector<StampedPose>& est, const std::vector<StampedPose>& gt,
                                  double max_difference) {
  Correspondences c;
  for (const auto& [g, e] : associate(gt, est, max_difference)) {
    c.model.push_back(est[e].pose.position);
    c.data.push_back(gt[g].pose.position);
  }
  return c;
}

ErrorStatistics errors_under(const RigidAlignment& a, const Correspondences& c) {
  std::vector<double> e(c.model.size());
  for (size_t k = 0; k < e.size(); ++k) e[k] = (a(c.model[k]) - c.data[k]).norm();
  return statistics_of(std::move(e));
}

}  // namespace

FleetEvaluation evaluate_fleet(const std::map<std::string, std::vector<StampedPose>>& keyframes,
                               const LandmarkPositions& landmarks,
                               const std::map<std::string, std::vector<StampedPose>>& truth,
                               const LandmarkPositions& landmark_truth, const FleetEvaluationOptions& o) {
  std::map<std::string, Correspondences> per_robot;
  Correspondences all, lm;
  for (const auto& [body, est] : keyframes) {
    const auto gt = truth.find(body);
    if (gt == truth.end()) continue;
    Correspondences c = matched_keyframes(est, gt->second, o.max_difference);
    if (c.model.size() < 2) continue;
    all.model.insert(all.model.end(), c.model.begin(), c.model.end());
    all.data.insert(all.data.end(), c.data.begin(), c.data.end());
    per_robot.emplace(body, std::move(c));
  }
  for (const auto& [id, p] : landmarks)
    if (const auto it = landmark_truth.find(id); it != landmark_truth.end()) {
      lm.model.push_back(p);
      lm.data.push_back(it->second);
    }
  all.model.insert(all.model.end(), lm.model.begin(), lm.model.end());
  all.data.insert(all.data.end(), lm.data.begin(), lm.data.end());
  if (all.model.size() < 2)
    throw std::invalid_argument("fleet evaluation: only " + std::to_string(all.model.size()) +
                                " keyframe(s) and landmark(s) have ground truth; at least 2 are needed");
  FleetEvaluation r;
  r.alignment = align_points(all.matrix(all.model), all.matrix(all.data), false, o.planar);
  for (const auto& [body, c] : per_robot) {
    FleetRobotError& e = r.robots[body];
    e.fleet = errors_under(r.alignment, c);
    e.own = errors_under(align_points(c.matrix(c.model), c.matrix(c.data), false, o.planar), c);
    e.matched = c.model.size();
    e.keyframes = keyframes.at(body).size();
  }
  r.landmarks = errors_under(r.alignment, lm);
  r.landmarks_estimated = landmarks.size();
  return r;
}

}  // namespace sextant::tools
