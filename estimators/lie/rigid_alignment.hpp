#pragma once
// The similarity (or rigid motion) that best maps one set of points onto another in the least-squares sense:
//     min over s, R, t of  sum_k | s R model_k + t - data_k |^2,
// Umeyama, "Least-squares estimation of transformation parameters between two point patterns", PAMI 1991 (as the
// TUM benchmark's evaluate_ate.py computes it; s fixed at 1 unless asked: Kabsch).  A planar alignment uses the x
// and y rows only: a rotation about z and a translation in x, y.  One home for both users: the fleet's frame
// placement (estimators/slam/frame_placement.hpp) and the trajectory evaluation (eval/).
#include "estimators/lie/se3.hpp"

#include <Eigen/Core>

namespace sextant {

/// x -> scale * rotation * x + translation.
struct RigidAlignment {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  double scale = 1.0;
  Eigen::Vector3d operator()(const Eigen::Vector3d& x) const { return scale * rotation * x + translation; }
  /// The rigid part as an SE(3) (the scale left out).
  SE3 motion() const;
};

/// The alignment of the columns of `model` onto those of `data` (see above).  Needs at least 2 corresponding
/// columns (throws std::invalid_argument otherwise); with fewer than 3 non-collinear points a 3-D rotation is not
/// determined (the SVD picks one).
RigidAlignment align_points(const Eigen::Matrix3Xd& model, const Eigen::Matrix3Xd& data, bool estimate_scale = false,
                            bool planar = false);

}  // namespace sextant
