#include "estimators/filter/state_augmentation.hpp"

#include "estimators/spd_matrix.hpp"

#include <stdexcept>

namespace sextant::filter {

Eigen::MatrixXd augmented_covariance(const Eigen::MatrixXd& P, const Eigen::MatrixXd& Jx, const Eigen::MatrixXd& Jz,
                                     const Eigen::MatrixXd& R) {
  const Eigen::Index n = P.rows(), m = Jx.rows(), k = Jx.cols();
  if (P.cols() != n || k > n || Jz.rows() != m || Jz.cols() != m || R.rows() != m || R.cols() != m)
    throw std::invalid_argument("augmented_covariance: Jx must be m x k with k <= n, Jz and R m x m");
  Eigen::MatrixXd out(n + m, n + m);
  out.topLeftCorner(n, n) = P;
  const Eigen::MatrixXd cross = Jx * P.topRows(k);  // m x n
  out.bottomLeftCorner(m, n) = cross;
  out.topRightCorner(n, m) = cross.transpose();
  const Eigen::MatrixXd Pll = Jx * P.topLeftCorner(k, k) * Jx.transpose() + Jz * R * Jz.transpose();
  out.bottomRightCorner(m, m) = symmetrized(Pll);
  return out;
}

}  // namespace sextant::filter
