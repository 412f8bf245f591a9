// The covariance regularization (eigenvalue_floor.hpp) against matrices built from a known eigendecomposition.
#include "estimators/filter/eigenvalue_floor.hpp"

#include <doctest/doctest.h>

#include <Eigen/Geometry>

using sextant::filter::floor_eigenvalues;

namespace {
// V diag(l) V' with V a fixed rotation.
Eigen::Matrix3d with_eigenvalues(const Eigen::Vector3d& l) {
  const Eigen::Matrix3d V = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  return V * l.asDiagonal() * V.transpose();
}
}  // namespace

TEST_CASE("floor_eigenvalues: eigenvalues below the floor are raised to it, the others and the eigenvectors kept") {
  const Eigen::Matrix3d m = with_eigenvalues({-0.5, 1e-12, 2.0});
  const Eigen::Matrix3d expected = with_eigenvalues({1e-3, 1e-3, 2.0});
  CHECK((floor_eigenvalues<3>(m, 1e-3) - expected).cwiseAbs().maxCoeff() < 1e-12);
  // Floor 0: the nearest PSD matrix (Higham 1988), here V diag(0, 1e-12, 2) V'.
  CHECK((floor_eigenvalues<3>(m, 0.0) - with_eigenvalues({0, 1e-12, 2.0})).cwiseAbs().maxCoeff() < 1e-12);
  // A matrix already above the floor is unchanged; an asymmetric one is symmetrized first.
  const Eigen::Matrix3d pd = with_eigenvalues({0.1, 0.5, 2.0});
  CHECK((floor_eigenvalues<3>(pd, 1e-3) - pd).cwiseAbs().maxCoeff() < 1e-12);
  Eigen::Matrix3d skewed = pd;
  skewed(0, 1) += 0.2;
  skewed(1, 0) -= 0.2;
  CHECK((floor_eigenvalues<3>(skewed, 1e-3) - pd).cwiseAbs().maxCoeff() < 1e-12);
  // 6x6: the smallest eigenvalue of the result is the floor.
  Eigen::Matrix<double, 6, 6> big = Eigen::Matrix<double, 6, 6>::Zero();
  big(0, 0) = -1;
  big(5, 5) = 3;
  const Eigen::Matrix<double, 6, 6> f = floor_eigenvalues<6>(big, 1e-6);
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eig(f);
  CHECK(eig.eigenvalues().minCoeff() == doctest::Approx(1e-6).epsilon(1e-9));
  CHECK(eig.eigenvalues().maxCoeff() == doctest::Approx(3.0));
}
