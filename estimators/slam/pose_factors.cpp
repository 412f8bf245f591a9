#include "estimators/slam/pose_factors.hpp"

#include "estimators/lie/planar_axes.hpp"
#include "estimators/lie/se2.hpp"
#include "estimators/spd_matrix.hpp"

#include <Eigen/Cholesky>

namespace sextant::slam {

Matrix6d residual_information(const Matrix6d& tangent_information) {
  Matrix6d out = tangent_information;
  out.bottomRows<3>() *= 2;
  out.rightCols<3>() *= 2;
  return out;
}

std::unique_ptr<graph::Factor> odometry_factor(bool planar, int from, int to, const SE3& edge,
                                               const Matrix6d& covariance) {
  const Eigen::MatrixXd cov = planar ? Eigen::MatrixXd(planar_block(covariance)) : Eigen::MatrixXd(covariance);
  if (!is_positive_definite(cov)) return nullptr;
  const Eigen::MatrixXd information = symmetrized(cov.llt().solve(Eigen::MatrixXd::Identity(cov.rows(), cov.cols())));
  if (planar)
    return std::make_unique<graph::RelativePoseFactor>(from, to, SE2::from_se3(edge), Eigen::Matrix3d(information));
  return std::make_unique<graph::RelativePoseFactor>(from, to, edge, residual_information(information));
}

std::unique_ptr<graph::Factor> loop_factor(bool planar, int from, int to, const SE3& z, const Matrix6d& information) {
  if (planar)
    return std::make_unique<graph::RelativePoseFactor>(from, to, SE2::from_se3(z),
                                                       Eigen::Matrix3d(planar_block(information)));
  return std::make_unique<graph::RelativePoseFactor>(from, to, z, residual_information(information));
}

}  // namespace sextant::slam
