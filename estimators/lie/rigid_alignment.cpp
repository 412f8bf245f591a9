#include "estimators/lie/rigid_alignment.hpp"

#include <Eigen/SVD>

#include <cmath>
#include <stdexcept>

namespace sextant {

SE3 RigidAlignment::motion() const { return SE3(SO3(Eigen::Quaterniond(rotation)), translation); }

RigidAlignment align_points(const Eigen::Matrix3Xd& a, const Eigen::Matrix3Xd& b, bool planar, bool estimate_scale,
                            const Eigen::VectorXd& weights) {
  const Eigen::Index n = a.cols();
  if (n == 0 || b.cols() != n || (weights.size() != 0 && weights.size() != n))
    throw std::invalid_argument("align_points: two point sets of the same non-zero size (and as many weights)");
  const Eigen::VectorXd w = weights.size() == 0 ? Eigen::VectorXd::Ones(n) : weights;
  const double total = w.sum();
  const Eigen::Vector3d mu_a = a * w / total, mu_b = b * w / total;
  Eigen::Matrix3Xd ac = a.colwise() - mu_a, bc = b.colwise() - mu_b;
  RigidAlignment r;
  if (planar) {
    ac.row(2).setZero();
    bc.row(2).setZero();
    double cross = 0, dot = 0;
    for (Eigen::Index k = 0; k < n; ++k) {
      cross += w[k] * (ac(0, k) * bc(1, k) - ac(1, k) * bc(0, k));
      dot += w[k] * (ac(0, k) * bc(0, k) + ac(1, k) * bc(1, k));
    }
    r.rotation = Eigen::AngleAxisd(std::atan2(cross, dot), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    r.translation = mu_b - r.rotation * mu_a;
    r.translation.z() = 0;
    return r;
  }
  const Eigen::Matrix3d cov = bc * w.asDiagonal() * ac.transpose();
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(cov, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) S(2, 2) = -1;
  r.rotation = svd.matrixU() * S * svd.matrixV().transpose();
  if (estimate_scale) {
    const double var_a = (ac * w.cwiseSqrt().asDiagonal()).squaredNorm();
    if (var_a > 0) r.scale = (svd.singularValues().asDiagonal() * S).trace() / var_a;
  }
  r.translation = mu_b - r.scale * r.rotation * mu_a;
  return r;
}

}  // namespace sextant
