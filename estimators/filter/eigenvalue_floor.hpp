#pragma once
// The one regularization of a covariance-like matrix that sextant uses: symmetrize, then floor the eigenvalues.
// With floor 0 this is the nearest positive semi-definite matrix in the Frobenius norm (Higham, "Computing a nearest
// symmetric positive semidefinite matrix", Linear Algebra Appl. 103, 1988); with floor v > 0 every eigenvalue is at
// least v, so the matrix is positive definite with its inverse bounded by 1/v.  Directions already above the floor
// are left as they are.
#include <Eigen/Core>
#include <Eigen/Eigenvalues>

namespace sextant::filter {

template <int N>
Eigen::Matrix<double, N, N> floor_eigenvalues(const Eigen::Matrix<double, N, N>& m, double floor) {
  const Eigen::Matrix<double, N, N> s = 0.5 * (m + m.transpose());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> eig(s);
  return eig.eigenvectors() * eig.eigenvalues().cwiseMax(floor).asDiagonal() * eig.eigenvectors().transpose();
}

}  // namespace sextant::filter
