#include "estimators/lie/rigid_alignment.hpp"

#include <Eigen/SVD>

#include <stdexcept>

namespace sextant {
namespace {

// Umeyama in D dimensions (the first D rows of the points).
template <int D>
RigidAlignment align_in(const Eigen::Matrix3Xd& model, const Eigen::Matrix3Xd& data, bool estimate_scale) {
  using Vector = Eigen::Matrix<double, D, 1>;
  using Matrix = Eigen::Matrix<double, D, D>;
  const Eigen::Matrix<double, D, Eigen::Dynamic> m = model.topRows<D>(), d = data.topRows<D>();
  const Vector mu_m = m.rowwise().mean(), mu_d = d.rowwise().mean();
  const Eigen::Matrix<double, D, Eigen::Dynamic> mc = m.colwise() - mu_m, dc = d.colwise() - mu_d;
  // W' = sum data_c model_c' (evaluate_ate.py's align(); Umeyama 1991 with the 1/n dropped).
  const Matrix Wt = dc * mc.transpose();
  Eigen::JacobiSVD<Matrix> svd(Wt, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Matrix S = Matrix::Identity();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) S(D - 1, D - 1) = -1;
  RigidAlignment r;
  const Matrix R = svd.matrixU() * S * svd.matrixV().transpose();
  r.rotation.topLeftCorner<D, D>() = R;
  if (estimate_scale) r.scale = (svd.singularValues().asDiagonal() * S).trace() / mc.squaredNorm();
  r.translation.head<D>() = mu_d - r.scale * R * mu_m;
  return r;
}

}  // namespace

SE3 RigidAlignment::motion() const { return SE3(SO3(Eigen::Quaterniond(rotation)), translation); }

RigidAlignment align_points(const Eigen::Matrix3Xd& model, const Eigen::Matrix3Xd& data, bool estimate_scale,
                            bool planar) {
  if (model.cols() != data.cols() || model.cols() < 2)
    throw std::invalid_argument("alignment: at least 2 corresponding points are needed");
  return planar ? align_in<2>(model, data, estimate_scale) : align_in<3>(model, data, estimate_scale);
}

}  // namespace sextant
