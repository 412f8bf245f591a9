#pragma once
// Trajectory evaluation with the exact semantics of the TUM RGB-D benchmark tools (associate.py, evaluate_ate.py,
// evaluate_rpe.py), so sextant's numbers are the numbers everyone cites.
//  - Association: every (gt, est) stamp pair closer than max_difference, sorted by |difference| (then by the gt
//    and est stamps), taken greedily one-to-one.
//  - ATE: rigid alignment of the matched positions (Kabsch/Umeyama without scale; with scale = Sim(3), Umeyama
//    1991), then the statistics of |R s p + t - q|.
//  - RPE: pairs (i, j) of estimated poses with j the pose closest to stamp_i + delta (seconds) or i + delta (frames),
//    dropping pairs whose j is the last pose; ground truth by nearest stamp within 2 x the median gt interval;
//    E = (P_j^-1 P_i)^-1 (Q_j^-1 Q_i); translational error |t_E|, rotational error acos((tr R_E - 1) / 2).
#include "estimators/lie/rigid_alignment.hpp"
#include "eval/trajectory_io.hpp"

#include <utility>
#include <vector>

namespace sextant::tools {

/// Index pairs (gt, est) of the one-to-one association, sorted by gt stamp.
std::vector<std::pair<size_t, size_t>> associate(const std::vector<StampedPose>& gt,
                                                 const std::vector<StampedPose>& est, double max_difference = 0.02,
                                                 double offset = 0.0);

struct ErrorStatistics {
  double rmse = 0, mean = 0, median = 0, std = 0, min = 0, max = 0;
  size_t count = 0;
};

/// Statistics as numpy computes them (population std, median of an even count = mean of the middle two).
ErrorStatistics statistics_of(std::vector<double> errors);

// The alignment (Umeyama; SE(2) when planar) lives in estimators/lie/rigid_alignment.hpp.
using sextant::align_points;
using sextant::RigidAlignment;

struct AteResult {
  ErrorStatistics error;  // metres
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  double scale = 1.0;
  size_t matched = 0;
  std::vector<double> stamps, errors;  // per matched pose: the estimate's stamp (s) and its aligned error (m)
};

/// ATE over associated pairs; `estimate_scale` = Sim(3) alignment.  Throws std::invalid_argument with fewer
/// than 2 matches.
AteResult absolute_trajectory_error(const std::vector<StampedPose>& gt, const std::vector<StampedPose>& est,
                                    bool estimate_scale = false, double max_difference = 0.02);

struct RpeResult {
  ErrorStatistics translation;   // metres per delta
  ErrorStatistics rotation_deg;  // degrees per delta
  size_t pairs = 0;
  std::vector<double> stamps, translation_errors, rotation_errors_deg;  // per pair, at the stamp of its first pose
};

enum class DeltaUnit { kSeconds, kFrames };

/// RPE in the TUM tool's --fixed_delta mode.  Throws std::invalid_argument when no pair can be formed.
RpeResult relative_pose_error(const std::vector<StampedPose>& gt, const std::vector<StampedPose>& est,
                              double delta = 1.0, DeltaUnit unit = DeltaUnit::kSeconds, double scale = 1.0);

}  // namespace sextant::tools
