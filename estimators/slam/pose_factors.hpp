#pragma once
// The smoother's factors for odometry edges and loops between keyframes, from covariances and informations over
// sextant's tangent [t; phi] (rotation in radians; a planar body's at x, y, yaw of the 6x6).
//
// A 3-D RelativePoseFactor's residual is g2o's [t_E; vec(q_E)] with vec(q_E) ~ phi / 2, so [t; phi] ~ T [t_E; vec(q_E)],
// T = diag(I, 2 I), and its information is T Omega T: the rotation block times 4, the cross blocks times 2 (the
// inverse of tools::g2o_information_to_sextant).  Passing Omega unchanged weighted every rotation 4 times too little.
#include "estimators/graph/factor.hpp"
#include "estimators/lie/se3.hpp"

#include <memory>

namespace sextant::slam {

/// The residual information of a 3-D RelativePoseFactor from an information over the tangent (see above).
Matrix6d residual_information(const Matrix6d& tangent_information);

/// The factor of an odometry edge `edge` from keyframe variable `from` to `to` with covariance `covariance`; nullptr
/// when that covariance is not positive definite on the body's axes (spd_matrix.hpp's check: bad input, refused).
std::unique_ptr<graph::Factor> odometry_factor(bool planar, int from, int to, const SE3& edge,
                                               const Matrix6d& covariance);

/// The factor of a loop z between keyframe variables with information `information` over the tangent.
std::unique_ptr<graph::Factor> loop_factor(bool planar, int from, int to, const SE3& z, const Matrix6d& information);

}  // namespace sextant::slam
