#include "estimators/filter/spatial_ekf.hpp"

#include "estimators/filter/landmark_admission.hpp"
#include "estimators/lie/lie_archive.hpp"

#include "estimators/filter/state_augmentation.hpp"
#include "estimators/lie/so2.hpp"
#include "estimators/spd_matrix.hpp"

#include <cmath>

namespace sextant::filter {

void SpatialEkf::initialize(const SE3& pose, const Matrix6& covariance) {
  pose_ = pose;
  landmarks_.resize(0);
  P_ = covariance;
  slot_.clear();
  initialized_ = true;
}

Health SpatialEkf::predict(const SE3& delta, const Matrix6& Q) {
  const Matrix6 F = delta.inverse().adjoint();
  const SE3 pose = pose_ * delta;
  const Eigen::Index n = P_.rows();
  Matrix6 Prr = F * P_.topLeftCorner<6, 6>() * F.transpose() + Q;
  Prr = symmetrized(Prr);
  const Eigen::MatrixXd Prl = F * P_.topRightCorner(6, n - 6);
  Eigen::Matrix<double, 7, 1> p;
  p << pose.translation(), pose.rotation().quaternion().coeffs();
  Health h = estimate_health(p, Prr, 6);
  if (h == Health::kHealthy && !Prl.allFinite()) h = Health::kNonFinite;
  if (h != Health::kHealthy) {
    refusals_.count(h);
    return h;
  }
  pose_ = pose;
  P_.topLeftCorner<6, 6>() = Prr;
  if (n > 6) {
    P_.topRightCorner(6, n - 6) = Prl;
    P_.bottomLeftCorner(n - 6, 6) = Prl.transpose();
  }
  return h;
}

UpdateResult SpatialEkf::counted(UpdateResult r) {
  if (r.reason == UpdateReason::kNonFinite)
    refusals_.count(Health::kNonFinite);
  else if (r.reason == UpdateReason::kIndefinite)
    refusals_.count(Health::kIndefinite);
  return r;
}

Eigen::Vector3d SpatialEkf::observation(const SE3& X, const Eigen::Vector3d& l, Eigen::Matrix<double, 3, 6>* Hx,
                                        Eigen::Matrix3d* Hl) {
  const Eigen::Matrix3d Rt = X.rotation().matrix().transpose();
  const Eigen::Vector3d q = Rt * (l - X.translation());
  const double sxy2 = q.x() * q.x() + q.y() * q.y(), sxy = std::sqrt(sxy2), r2 = q.squaredNorm(), r = std::sqrt(r2);
  Eigen::Matrix3d dh_dq;
  dh_dq.row(0) = q.transpose() / r;
  dh_dq.row(1) << -q.y() / sxy2, q.x() / sxy2, 0;
  dh_dq.row(2) << -q.z() * q.x() / (sxy * r2), -q.z() * q.y() / (sxy * r2), sxy / r2;
  if (Hx) {
    Hx->leftCols<3>() = -dh_dq;
    Hx->rightCols<3>() = dh_dq * SO3::hat(q);
  }
  if (Hl) *Hl = dh_dq * Rt;
  return {r, std::atan2(q.y(), q.x()), std::atan2(q.z(), sxy)};
}

Eigen::Vector3d SpatialEkf::inverse_observation(const SE3& X, const Eigen::Vector3d& z, Eigen::Matrix<double, 3, 6>* Jx,
                                                Eigen::Matrix3d* Jz) {
  const double r = z[0], ca = std::cos(z[1]), sa = std::sin(z[1]), ce = std::cos(z[2]), se = std::sin(z[2]);
  const Eigen::Vector3d q(r * ce * ca, r * ce * sa, r * se);
  const Eigen::Matrix3d R = X.rotation().matrix();
  if (Jx) {
    Jx->leftCols<3>() = R;
    Jx->rightCols<3>() = -R * SO3::hat(q);
  }
  if (Jz) {
    Eigen::Matrix3d dq;
    dq.col(0) << ce * ca, ce * sa, se;
    dq.col(1) << -r * ce * sa, r * ce * ca, 0;
    dq.col(2) << -r * se * ca, -r * se * sa, r * ce;
    *Jz = R * dq;
  }
  return X.translation() + R * q;
}

UpdateResult SpatialEkf::observe(int64_t id, const Eigen::Vector3d& z, const Eigen::Matrix3d& R) {
  UpdateResult out;
  if (!z.allFinite() || !R.allFinite() || z[0] <= 0) {
    out.reason = UpdateReason::kNonFinite;
    return out;
  }
  auto s = slot_.find(id);
  if (s == slot_.end())
    return counted(
        admit_new_landmark(options_.slam, id, slot_.size(), options_.max_landmarks, [&] { return augment(id, z, R); }));
  const int k = s->second;
  Eigen::Matrix<double, 3, 6> Hx;
  Eigen::Matrix3d Hl;
  const Eigen::Vector3d h = observation(pose_, landmarks_.segment<3>(k - 6), &Hx, &Hl);
  if (h[0] < 1e-6 || !Hx.allFinite()) {
    out.reason = UpdateReason::kSingular;
    return out;
  }
  Eigen::VectorXd r = z - h;
  r[1] = wrap_angle(r[1]);
  // H is zero but for the pose's 6 columns and the landmark's 3: P H' and H P H' in O(n).
  const Eigen::MatrixXd PHt = P_.leftCols<6>() * Hx.transpose() + P_.middleCols<3>(k) * Hl.transpose();
  const Eigen::MatrixXd HPHt = Hx * PHt.topRows<6>() + Hl * PHt.middleRows<3>(k);
  Eigen::VectorXd dx = Eigen::VectorXd::Zero(P_.rows());
  out = counted(kalman_update_from(dx, P_, r, PHt, HPHt, R, options_.gate));
  if (out.accepted) {
    pose_ = pose_ * SE3::exp(dx.head<6>());
    landmarks_ += dx.tail(dx.size() - 6);
  }
  return out;
}

Health SpatialEkf::augment(int64_t id, const Eigen::Vector3d& z, const Eigen::Matrix3d& R) {
  const Eigen::Index n = P_.rows();
  Eigen::Matrix<double, 3, 6> Jx;
  Eigen::Matrix3d Jz;
  const Eigen::Vector3d l = inverse_observation(pose_, z, &Jx, &Jz);
  Eigen::MatrixXd P = augmented_covariance(P_, Jx, Jz, R);
  // Only the new rows are new: their block must be a covariance and every number finite.
  Health h = estimate_health(l, P.bottomRightCorner<3, 3>(), 3);
  if (h == Health::kHealthy && !P.bottomRows<3>().allFinite()) h = Health::kNonFinite;
  if (h != Health::kHealthy) return h;
  landmarks_.conservativeResize(landmarks_.size() + 3);
  landmarks_.tail<3>() = l;
  P_ = std::move(P);
  slot_[id] = static_cast<int>(n);
  return h;
}

std::map<int64_t, Eigen::Vector3d> SpatialEkf::landmarks() const {
  std::map<int64_t, Eigen::Vector3d> out;
  for (const auto& [id, k] : slot_) out[id] = landmarks_.segment<3>(k - 6);
  return out;
}

void SpatialEkf::save(archive::ArchiveWriter& w) const {
  w(initialized_)(pose_)(landmarks_)(P_)(slot_)(refusals_.non_finite)(refusals_.indefinite);
}

void SpatialEkf::load(archive::ArchiveReader& r) {
  r(initialized_)(pose_)(landmarks_)(P_)(slot_)(refusals_.non_finite)(refusals_.indefinite);
  if (landmarks_.size() % 3 != 0 || P_.rows() != 6 + landmarks_.size() || P_.cols() != P_.rows())
    r.fail("a 3-D EKF state whose covariance does not match it");
  for (const auto& [id, slot] : slot_)
    if (slot < 6 || slot + 3 > 6 + landmarks_.size()) r.fail("a 3-D EKF landmark slot outside the state");
}

}  // namespace sextant::filter
