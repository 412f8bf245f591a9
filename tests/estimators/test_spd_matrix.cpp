// Covariance and information matrices (estimators/spd_matrix.hpp): the symmetrization by hand, also assigned back
// (the in-place form m = 0.5 * (m + m') aliases in Eigen), the positive-definiteness check on matrices of known definiteness, and the regularization against
// matrices built from a known eigendecomposition.
#include "estimators/spd_matrix.hpp"

#include <doctest/doctest.h>

#include <Eigen/Geometry>

#include <Eigen/QR>

#include <cmath>
#include <cstdlib>
#include <limits>

using namespace sextant;

namespace {
// V diag(l) V' with V a fixed rotation.
Eigen::Matrix3d with_eigenvalues(const Eigen::Vector3d& l) {
  const Eigen::Matrix3d V = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  return V * l.asDiagonal() * V.transpose();
}
}  // namespace

TEST_CASE("symmetrized: (m + m') / 2 exactly, also when assigned back to m") {
  Eigen::Matrix3d m;
  m << 1, 2, 3, 4, 5, 6, 7, 8, 9;
  Eigen::Matrix3d expected;
  expected << 1, 3, 5, 3, 5, 7, 5, 7, 9;
  const Eigen::Matrix3d a = m;
  m = symmetrized(m);  // assigning back is safe
  CHECK(m == expected);
  CHECK(m == m.transpose());
  // Dynamic size and expressions.
  const Eigen::MatrixXd d = Eigen::MatrixXd(a) * 2.0;
  CHECK(symmetrized(d) == Eigen::MatrixXd(expected * 2.0));
  CHECK(symmetrized(a + Eigen::Matrix3d::Identity()) == Eigen::Matrix3d(expected + Eigen::Matrix3d::Identity()));
}

TEST_CASE("check_positive_definite: finite, symmetric, smallest eigenvalue above zero, the problem says which") {
  using P = DefinitenessCheck::Problem;
  const Eigen::Matrix3d pd = with_eigenvalues({0.1, 0.5, 2.0});
  const DefinitenessCheck good = check_positive_definite(pd);
  CHECK(good.ok());
  CHECK(smallest_eigenvalue(pd) == doctest::Approx(0.1));
  CHECK(is_positive_definite(pd));

  const DefinitenessCheck indefinite = check_positive_definite(with_eigenvalues({-0.2, 0.5, 2.0}));
  CHECK(indefinite.problem == P::kNotPositiveDefinite);
  CHECK(indefinite.smallest_eigenvalue == doctest::Approx(-0.2));
  CHECK(check_positive_definite(with_eigenvalues({0.0, 0.5, 2.0})).problem == P::kNotPositiveDefinite);  // singular
  CHECK_FALSE(is_positive_definite(Eigen::Matrix2d::Zero()));

  Eigen::Matrix3d nan = pd;
  nan(1, 2) = std::numeric_limits<double>::quiet_NaN();
  CHECK(check_positive_definite(nan).problem == P::kNotFinite);
  Eigen::Matrix3d inf = pd;
  inf(0, 0) = std::numeric_limits<double>::infinity();
  CHECK(check_positive_definite(inf).problem == P::kNotFinite);

  // Symmetric to 1e-9 of max(1, largest entry): rounding passes, a real asymmetry does not.
  Eigen::Matrix3d rounded = pd;
  rounded(0, 1) += 1e-12;
  CHECK(check_positive_definite(rounded).ok());
  Eigen::Matrix3d skewed = pd;
  skewed(0, 1) += 1e-6;
  CHECK(check_positive_definite(skewed).problem == P::kNotSymmetric);
  Eigen::MatrixXd big = Eigen::MatrixXd(pd) * 1e6;
  big(0, 1) += 1e-4;  // 1e-10 of the largest entry
  CHECK(check_positive_definite(big).ok());
}

TEST_CASE("cholesky_certifies_positive_definite: never certifies what the eigenvalues call indefinite") {
  // Random orthogonal bases, spectra from clearly definite to singular and indefinite, sizes 2, 3, 6 (fixed and
  // dynamic) and 4 (dynamic only): a certificate implies a positive smallest eigenvalue, and a spectrum clearly
  // above zero (condition below 1e8) is always certified, so the eigenvalues are computed only for the rare rest.
  std::srand(7);
  int certified = 0, cases = 0;
  for (int n : {2, 3, 4, 6})
    for (double smallest : {1.0, 1e-3, 1e-8, 1e-14, 0.0, -1e-14, -1e-3}) {
      for (int trial = 0; trial < 25; ++trial, ++cases) {
        const Eigen::MatrixXd q = Eigen::MatrixXd::Random(n, n).householderQr().householderQ();
        Eigen::VectorXd l = (Eigen::VectorXd::Random(n).array() + 2.0).matrix() * 1e3;
        l[0] = smallest * 1e3;
        const Eigen::MatrixXd m = symmetrized(q * l.asDiagonal() * q.transpose());
        const bool cert = cholesky_certifies_positive_definite(m);
        certified += cert ? 1 : 0;
        if (cert) CHECK(smallest_eigenvalue(m) > 0);
        if (smallest >= 1e-3) CHECK(cert);
        if (smallest < 0) CHECK_FALSE(check_positive_definite(m).ok());
        if (n == 3) CHECK(cholesky_certifies_positive_definite(Eigen::Matrix3d(m)) == cert);
      }
    }
  CHECK(certified >= 4 * 3 * 25);  // at least the spectra 1, 1e-3 and 1e-8 of every size
  CHECK(certified < cases);
}

TEST_CASE("floor_eigenvalues: eigenvalues below the floor are raised to it, the others and the eigenvectors kept") {
  const Eigen::Matrix3d m = with_eigenvalues({-0.5, 1e-12, 2.0});
  const Eigen::Matrix3d expected = with_eigenvalues({1e-3, 1e-3, 2.0});
  CHECK((floor_eigenvalues(m, 1e-3) - expected).cwiseAbs().maxCoeff() < 1e-12);
  // Floor 0: the nearest PSD matrix (Higham 1988), here V diag(0, 1e-12, 2) V'.
  CHECK((floor_eigenvalues(m, 0.0) - with_eigenvalues({0, 1e-12, 2.0})).cwiseAbs().maxCoeff() < 1e-12);
  // A matrix already above the floor is unchanged; an asymmetric one is symmetrized first.
  const Eigen::Matrix3d pd = with_eigenvalues({0.1, 0.5, 2.0});
  CHECK((floor_eigenvalues(pd, 1e-3) - pd).cwiseAbs().maxCoeff() < 1e-12);
  Eigen::Matrix3d skewed = pd;
  skewed(0, 1) += 0.2;
  skewed(1, 0) -= 0.2;
  CHECK((floor_eigenvalues(skewed, 1e-3) - pd).cwiseAbs().maxCoeff() < 1e-12);
  // 6x6 and dynamic size: the smallest eigenvalue of the result is the floor.
  Eigen::Matrix<double, 6, 6> big = Eigen::Matrix<double, 6, 6>::Zero();
  big(0, 0) = -1;
  big(5, 5) = 3;
  for (const Eigen::MatrixXd& f :
       {Eigen::MatrixXd(floor_eigenvalues(big, 1e-6)), floor_eigenvalues(Eigen::MatrixXd(big), 1e-6)}) {
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(f);
    CHECK(eig.eigenvalues().minCoeff() == doctest::Approx(1e-6).epsilon(1e-9));
    CHECK(eig.eigenvalues().maxCoeff() == doctest::Approx(3.0));
    CHECK(is_positive_definite(f));
  }
}
