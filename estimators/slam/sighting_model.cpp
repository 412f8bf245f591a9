#include "estimators/slam/sighting_model.hpp"

#include "estimators/lie/planar_axes.hpp"
#include "estimators/lie/se2.hpp"
#include "estimators/spd_matrix.hpp"

#include <Eigen/Cholesky>

#include <cmath>

namespace sextant::slam {

SightingModel::SightingModel(bool planar, const SE3& keyframe_pose, const TrackPoint& anchor, const SE3& sensor_in_body)
    : planar_(planar),
      sensor_in_body_(sensor_in_body),
      sensor_in_keyframe_(anchor.motion * sensor_in_body),
      at_sighting_(keyframe_pose * anchor.motion),
      local_(2) {
  // The pose at the sighting X_K D and the landmark, as a two-variable problem to evaluate the factor on: its first
  // Jacobian is dh/dD (a right perturbation of X_K D is one of D).
  local_[0].kind = planar ? graph::VariableKind::kPose2 : graph::VariableKind::kPose3;
  local_[1].kind = planar ? graph::VariableKind::kPoint2 : graph::VariableKind::kPoint3;
  if (planar)
    local_[0].pose2 = SE2::from_se3(at_sighting_);
  else
    local_[0].pose3 = at_sighting_;
  sigma_d_ = planar ? Eigen::MatrixXd(planar_block(anchor.covariance)) : Eigen::MatrixXd(anchor.covariance);
  const Matrix6d ad6 = anchor.motion.inverse().adjoint();  // X_K Exp(xi) D = X_K D Exp(Ad(D^-1) xi)
  ad_ = planar ? Eigen::MatrixXd(planar_block(ad6)) : Eigen::MatrixXd(ad6);
}

graph::PointObservationFactor::Model SightingModel::model() const {
  return planar_ ? graph::PointObservationFactor::Model::kRangeBearing
                 : graph::PointObservationFactor::Model::kRangeAzimuthElevation;
}

bool SightingModel::measurement(const LandmarkSighting& s, Eigen::VectorXd& z, Eigen::MatrixXd& R) const {
  const int n = dimension();
  z.resize(n);
  z[0] = s.range, z[1] = s.azimuth;
  if (!planar_) z[2] = s.elevation;
  R = s.covariance.topLeftCorner(n, n);
  return z.allFinite() && s.range > 0 && is_positive_definite(R);
}

Eigen::Vector3d SightingModel::landmark_from(const LandmarkSighting& s) const {
  const double c = std::cos(planar_ ? 0.0 : s.elevation);
  const Eigen::Vector3d l(s.range * c * std::cos(s.azimuth), s.range * c * std::sin(s.azimuth),
                          planar_ ? 0.0 : s.range * std::sin(s.elevation));
  Eigen::Vector3d p = at_sighting_ * sensor_in_body_ * l;
  if (planar_) p.z() = 0;
  return p;
}

SightingModel::Evaluation SightingModel::evaluate(const Eigen::VectorXd& z, const Eigen::Vector3d& landmark) const {
  const int n = dimension();
  local_[1].point = landmark;
  const graph::PointObservationFactor probe(0, 1, model(), z, Eigen::MatrixXd::Identity(n, n), sensor_in_body_);
  graph::Linearization lin = probe.make_linearization(local_);
  probe.linearize(local_, lin);
  Evaluation ev;
  ev.odometry_part = lin.jacobians[0] * sigma_d_ * lin.jacobians[0].transpose();
  ev.error = std::move(lin.error);
  ev.d_motion = std::move(lin.jacobians[0]);
  ev.d_landmark = std::move(lin.jacobians[1]);
  return ev;
}

double SightingModel::mahalanobis(const Evaluation& ev, const Eigen::MatrixXd& R, double odometry_scale,
                                  const Eigen::MatrixXd& landmark_marginal,
                                  const Eigen::MatrixXd& keyframe_marginal) const {
  const double k2 = odometry_scale * odometry_scale;
  Eigen::MatrixXd S =
      landmark_marginal.size() > 0
          ? Eigen::MatrixXd(R + k2 * ev.odometry_part + ev.d_landmark * landmark_marginal * ev.d_landmark.transpose())
          : Eigen::MatrixXd(R + k2 * ev.odometry_part);
  if (keyframe_marginal.size() > 0) {
    const Eigen::MatrixXd jk = ev.d_motion * ad_;
    S += jk * keyframe_marginal * jk.transpose();
  }
  return ev.error.dot(S.ldlt().solve(ev.error));
}

Eigen::MatrixXd SightingModel::information(const Evaluation& ev, const Eigen::MatrixXd& R) const {
  const int n = dimension();
  const Eigen::MatrixXd cov = symmetrized(R + ev.odometry_part);
  return symmetrized(cov.llt().solve(Eigen::MatrixXd::Identity(n, n)));
}

}  // namespace sextant::slam
