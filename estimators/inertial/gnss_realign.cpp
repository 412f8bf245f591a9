#include "estimators/inertial/gnss_realign.hpp"

#include "estimators/spd_matrix.hpp"

namespace sextant::inertial {

Eigen::Matrix3d yaw_rotation(const PlanarAlignment& a) {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  R.topLeftCorner<2, 2>() = a.rotation();
  return R;
}

namespace {

Eigen::Vector3d shifted(const PlanarAlignment& a, const Eigen::Vector3d& p) {
  Eigen::Vector3d out = yaw_rotation(a) * p;
  out.head<2>() += a.translation;
  return out;
}

}  // namespace

EskfState realigned(const PlanarAlignment& a, const EskfState& x) {
  const Eigen::Matrix3d Rz = yaw_rotation(a);
  EskfState out = x;
  out.p = shifted(a, x.p);
  out.v = Rz * x.v;
  out.q = Eigen::Quaterniond(Rz * x.q.toRotationMatrix()).normalized();
  return out;
}

ErrorStateEkf::Matrix15 realigned_covariance(const PlanarAlignment& a, const EskfState& x,
                                             const ErrorStateEkf::Matrix15& P) {
  using E = ErrorStateEkf;
  const Eigen::Matrix3d Rz = yaw_rotation(a);
  E::Matrix15 J = E::Matrix15::Identity();
  J.block<3, 3>(E::kP, E::kP) = Rz;
  J.block<3, 3>(E::kV, E::kV) = Rz;
  E::Matrix15 out = J * P * J.transpose();
  out.block<2, E::kDim>(E::kP, 0).setZero();  // the horizontal position is the alignment's
  out.block<E::kDim, 2>(0, E::kP).setZero();

  const EskfState y = realigned(a, x);
  const Eigen::Vector3d ez = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d centroid = shifted(a, Eigen::Vector3d(a.track_centroid.x(), a.track_centroid.y(), 0));
  Eigen::Matrix<double, E::kDim, 3> G = Eigen::Matrix<double, E::kDim, 3>::Zero();
  G.block<2, 2>(E::kP, 0).setIdentity();
  G.block<3, 1>(E::kP, 2) = ez.cross(Eigen::Vector3d(y.p.x() - centroid.x(), y.p.y() - centroid.y(), 0));
  G.block<3, 1>(E::kV, 2) = ez.cross(y.v);
  G.block<3, 1>(E::kTheta, 2) = y.q.toRotationMatrix().transpose() * ez;
  const Eigen::Vector3d S(a.centroid_variance, a.centroid_variance, a.yaw_sigma * a.yaw_sigma);
  out += G * S.asDiagonal() * G.transpose();
  return symmetrized(out);
}

NavState realigned(const PlanarAlignment& a, const NavState& x) {
  const Eigen::Matrix3d Rz = yaw_rotation(a);
  return {Rz * x.R, Rz * x.v, shifted(a, x.p)};
}

}  // namespace sextant::inertial
