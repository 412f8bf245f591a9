#include "cli/trajectory_evaluation.hpp"

#include <cmath>
#include <stdexcept>

namespace sextant::tools {

Evaluation evaluate_trajectory(const std::vector<StampedPose>& gt, const std::vector<StampedPose>& est,
                               const EvaluationOptions& o) {
  Evaluation e;
  e.estimated_poses = est.size();
  e.ate = absolute_trajectory_error(gt, est, o.scale, o.max_difference);
  // RPE uses the same scale as the alignment, so a monocular estimate is compared at metric scale.
  try {
    e.rpe = relative_pose_error(gt, est, o.delta, o.delta_unit, e.ate.scale);
  } catch (const std::invalid_argument&) {
    e.rpe.reset();
  }
  // The KITTI error compares frame with frame: the associated pairs, in time order, at the alignment's scale.
  std::vector<engine::Pose> gt_pairs, est_pairs;
  for (const auto& [g, x] : associate(gt, est, o.max_difference)) {
    gt_pairs.push_back(gt[g].pose);
    engine::Pose p = est[x].pose;
    p.position *= e.ate.scale;
    est_pairs.push_back(p);
  }
  try {
    e.kitti = kitti_odometry_error(gt_pairs, est_pairs);
  } catch (const std::invalid_argument&) {
    e.kitti.reset();
  }
  return e;
}

Summary Evaluation::summary(const EvaluationOptions& o) const {
  Summary s;
  s.add("ate_rmse", ate.error.rmse).add("ate_mean", ate.error.mean).add("ate_median", ate.error.median);
  s.add("ate_std", ate.error.std).add("ate_min", ate.error.min).add("ate_max", ate.error.max);
  s.add("matched", ate.matched).add("estimated_poses", estimated_poses).add("scale", ate.scale);
  if (rpe) {
    s.add("rpe_trans_rmse", rpe->translation.rmse).add("rpe_trans_mean", rpe->translation.mean);
    s.add("rpe_rot_rmse_deg", rpe->rotation_deg.rmse).add("rpe_rot_mean_deg", rpe->rotation_deg.mean);
    s.add("rpe_pairs", rpe->pairs);
  } else {
    s.add("rpe_trans_rmse", std::nan("")).add("rpe_rot_rmse_deg", std::nan("")).add("rpe_pairs", 0);
  }
  if (kitti) {
    s.add("kitti_trans_pct", kitti->translation_percent).add("kitti_rot_deg_per_m", kitti->rotation_deg_per_m);
    s.add("kitti_segments", kitti->segments.size());
  } else {
    s.add("kitti_trans_pct", std::nan("")).add("kitti_rot_deg_per_m", std::nan("")).add("kitti_segments", 0);
  }
  s.add("rpe_delta", o.delta).add("rpe_delta_unit", o.delta_unit == DeltaUnit::kFrames ? "f" : "s");
  return s;
}

}  // namespace sextant::tools
