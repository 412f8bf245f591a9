#include "estimators/slam/loop_gate.hpp"

#include "estimators/lie/planar_axes.hpp"
#include "estimators/lie/se2.hpp"
#include "estimators/spd_matrix.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>

namespace sextant::slam {

KeyframeLoop loop_on_keyframes(bool planar, const SE3& relative, const Matrix6d& information, const TrackPoint& from,
                               const TrackPoint& to) {
  KeyframeLoop out;
  out.information = information;
  if (!from.covariance.isZero() || !to.covariance.isZero()) {
    out.widened = true;
    const Eigen::MatrixXd cov =
        (planar ? Eigen::MatrixXd(planar_block(information)) : Eigen::MatrixXd(information)).inverse();
    const Matrix6d extra = from.covariance + to.covariance;
    const Eigen::MatrixXd widened = cov + (planar ? Eigen::MatrixXd(planar_block(extra)) : Eigen::MatrixXd(extra));
    const Eigen::MatrixXd info = widened.inverse();
    out.information = planar ? embed_planar(info) : Matrix6d(symmetrized(info));
  }
  out.z = from.motion * relative * to.motion.inverse();
  return out;
}

double landing_sigma(const TrackPoint& from, const TrackPoint& to) {
  const Eigen::Matrix3d added = (from.covariance + to.covariance).topLeftCorner<3, 3>();
  if (added.isZero()) return 0;
  return std::sqrt(std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(added).eigenvalues().maxCoeff()));
}

double loop_mahalanobis(bool planar, const KeyframeLoop& loop, const SE3& predicted, const Matrix6d& path_covariance,
                        double odometry_scale) {
  const double k2 = odometry_scale * odometry_scale;
  if (planar) {
    const Eigen::Matrix3d info = planar_block(loop.information);
    const Eigen::Vector3d e = SE2::from_se3(loop.z).between(SE2::from_se3(predicted)).log();
    const Eigen::Matrix3d S = info.inverse() + k2 * planar_block(path_covariance);
    return e.dot(S.ldlt().solve(e));
  }
  const Vector6d e = loop.z.between(predicted).log();
  const Matrix6d S = loop.information.inverse() + odometry_scale * odometry_scale * path_covariance;
  return e.dot(S.ldlt().solve(e));
}

}  // namespace sextant::slam
