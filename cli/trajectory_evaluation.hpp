#pragma once
// `sextant eval` as a function, for the CLI and the Python module: ATE after alignment and RPE at the same scale
// (trajectory_eval.hpp, the TUM tools' semantics), summarized under the keys of `sextant eval --json`
// (the keys scripts depend on: ate_rmse, ate_mean, ate_median, ate_max, rpe_trans_rmse, rpe_rot_rmse_deg, matched, ...), and the KITTI
// odometry benchmark's drift per distance (kitti_odometry_metric.hpp) over the associated poses when the ground truth
// is long enough for its shortest segment (100 m).
#include "eval/kitti_odometry_metric.hpp"
#include "report/summary.hpp"
#include "eval/trajectory_eval.hpp"

#include <optional>

namespace sextant::tools {

struct EvaluationOptions {
  bool scale = false;  // Sim(3) alignment (monocular runs)
  double delta = 1.0;  // RPE delta
  DeltaUnit delta_unit = DeltaUnit::kSeconds;
  double max_difference = 0.02;  // association window, seconds
};

struct Evaluation {
  AteResult ate;
  std::optional<RpeResult> rpe;             // none when no pose pair has ground truth at both ends
  std::optional<KittiOdometryError> kitti;  // none when the associated ground truth is shorter than 100 m
  size_t estimated_poses = 0;
  /// The `sextant eval --json` keys (RPE keys null and rpe_pairs 0 without RPE; KITTI keys null and kitti_segments 0
  /// without the KITTI error).
  Summary summary(const EvaluationOptions& options) const;
};

/// Throws std::invalid_argument when fewer than 2 poses associate (no ATE).
Evaluation evaluate_trajectory(const std::vector<StampedPose>& gt, const std::vector<StampedPose>& est,
                               const EvaluationOptions& options = {});

}  // namespace sextant::tools
