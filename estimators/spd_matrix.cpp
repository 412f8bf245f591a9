#include "estimators/spd_matrix.hpp"

namespace sextant::spd_detail {
namespace {

/// f applied to m, or, for m of a pose's size (2, 3 or 6), to a fixed-size copy of it.
template <typename F>
auto at_fixed_size(const Eigen::Ref<const Eigen::MatrixXd>& m, F&& f) {
  if (m.rows() == m.cols()) switch (m.rows()) {
      case 2:
        return f(Eigen::Matrix2d(m));
      case 3:
        return f(Eigen::Matrix3d(m));
      case 6:
        return f(Eigen::Matrix<double, 6, 6>(m));
      default:
        break;
    }
  return f(Eigen::MatrixXd(m));
}

}  // namespace

double smallest_eigenvalue(const Eigen::Ref<const Eigen::MatrixXd>& m) {
  return at_fixed_size(m, [](const auto& a) { return smallest_eigenvalue_of(a); });
}

bool cholesky_certifies_positive_definite(const Eigen::Ref<const Eigen::MatrixXd>& m) {
  return at_fixed_size(m, [](const auto& a) { return cholesky_certifies(a); });
}

Eigen::Matrix2d floor_eigenvalues(const Eigen::Matrix2d& m, double floor) { return floored(m, floor); }
Eigen::Matrix3d floor_eigenvalues(const Eigen::Matrix3d& m, double floor) { return floored(m, floor); }
Eigen::Matrix<double, 6, 6> floor_eigenvalues(const Eigen::Matrix<double, 6, 6>& m, double floor) {
  return floored(m, floor);
}
Eigen::MatrixXd floor_eigenvalues(const Eigen::MatrixXd& m, double floor) { return floored(m, floor); }

}  // namespace sextant::spd_detail
