#pragma once
// The rigid motion that best maps one set of points onto another, in the least-squares sense:
//     min over R, t (and s) of  sum_k w_k | s R a_k + t - b_k |^2,
// Umeyama, "Least-squares estimation of transformation parameters between two point patterns", PAMI 1991 (the
// weighted form; with s fixed at 1 it is Kabsch's).  For planar points (z ignored) the rotation is about z alone:
// theta = atan2(sum w (a_c x b_c), sum w (a_c . b_c)) over the centred points.
#include "estimators/lie/se3.hpp"

#include <Eigen/Core>

namespace sextant {

struct RigidAlignment {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  double scale = 1.0;
  /// b ~ s R a + t as an SE(3) (the scale left out).
  SE3 motion() const;
};

/// The alignment mapping the columns of `a` onto those of `b` (same count, at least 1; weights all 1 when empty).
/// `planar`: a rotation about z and a translation in x, y only.  `estimate_scale`: Sim(3) (3-D only).
/// Throws std::invalid_argument for mismatched sizes or no point.
RigidAlignment align_points(const Eigen::Matrix3Xd& a, const Eigen::Matrix3Xd& b, bool planar,
                            bool estimate_scale = false, const Eigen::VectorXd& weights = {});

}  // namespace sextant
