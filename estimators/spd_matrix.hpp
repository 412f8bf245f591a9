#pragma once
// Covariance and information matrices: the one home of their symmetrization, of the positive-definiteness check and
// of their regularization, for every estimator (filters, graph, SLAM layer) and the bus's intake.
//
// The rule:
//  - Where a covariance or information enters as data (a message field at the bus's intake, a g2o edge, a factor
//    given to the optimizer or the incremental smoother, a sighting's covariance or an odometry edge in the SLAM
//    layer) it must be finite, symmetric (to 1e-9 of its largest entry, or of 1) and positive definite on the axes
//    it is used on (check_positive_definite).  One that is not is bad input: refused with the reason, never repaired
//    silently.  The intake drops and counts such a message (daemon/runtime/codec.cpp), the g2o reader lists such
//    edges in its error (repairing them, with floor_eigenvalues, only when the user asks for it), the optimizer and
//    the smoother refuse such a factor, the SLAM layer such an edge or sighting.
//  - The increment covariance every estimator composes or predicts with (dead reckoning, the EKFs, the particle
//    filter, the SLAM layer's odometry edges) is regularized one way: its eigenvalues on the body's axes floored at
//    the estimator's `min_increment_variance` (estimators/lie/pose_covariance.hpp, regularized_increment_covariance;
//    the planar EKF's increment_noise).  It is the sender's stated increment (positive definite: the intake checked
//    it) or the growth of its pose covariance between two messages, derived and possibly indefinite through rounding
//    or a reset of the sender; the floor keeps every prediction positive definite and a step without growth
//    invertible.  An estimator given an indefinite increment directly (not through the intake) floors it the same
//    way.  Covariances derived for publication are floored at 0 (nearest_psd), where a floor would inflate them.
//  - Symmetrizing is `symmetrized(m)`, never `m = 0.5 * (m + m.transpose())`: Eigen evaluates that in place,
//    coefficient by coefficient, so the upper triangle averages entries already averaged (aliasing) and the result
//    is not symmetric.
#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <type_traits>

namespace sextant {

/// (m + m') / 2, evaluated into a new matrix (safe to assign back to m).
template <typename Derived>
typename Derived::PlainObject symmetrized(const Eigen::MatrixBase<Derived>& m) {
  return (0.5 * (m + m.transpose())).eval();
}

// The decompositions below run in spd_matrix.cpp, instantiated there once for each size they are used at: a
// translation unit that checks or floors a matrix calls them and compiles none of Eigen's LLT or
// SelfAdjointEigenSolver itself (each costs seconds of compile time per size and per file).  A dynamic-size matrix of
// a pose's size (2, 3 or 6: planar and 3-D edges, every factor's information) is decomposed as a fixed-size copy: the
// same algorithm without heap allocation, which is most of the cost at these sizes.
namespace spd_detail {
double smallest_eigenvalue(const Eigen::Ref<const Eigen::MatrixXd>& m);
bool cholesky_certifies_positive_definite(const Eigen::Ref<const Eigen::MatrixXd>& m);
Eigen::Matrix2d floor_eigenvalues(const Eigen::Matrix2d& m, double floor);
Eigen::Matrix3d floor_eigenvalues(const Eigen::Matrix3d& m, double floor);
Eigen::Matrix<double, 6, 6> floor_eigenvalues(const Eigen::Matrix<double, 6, 6>& m, double floor);
Eigen::MatrixXd floor_eigenvalues(const Eigen::MatrixXd& m, double floor);

/// True for the square matrix types the kernels take: double, and dynamic or of a pose's size.
template <typename Plain>
constexpr bool kernel_size = std::is_same_v<typename Plain::Scalar, double> &&
                             (Plain::RowsAtCompileTime == Eigen::Dynamic || Plain::RowsAtCompileTime == 2 ||
                              Plain::RowsAtCompileTime == 3 || Plain::RowsAtCompileTime == 6) &&
                             Plain::RowsAtCompileTime == Plain::ColsAtCompileTime;

/// m as the kernels' argument: a fixed-size m copied into its plain type (on the stack), a dynamic one as it is (a
/// Ref binds a matrix or block without copying).
template <typename Derived>
decltype(auto) kernel_argument(const Eigen::MatrixBase<Derived>& m) {
  using Plain = typename Derived::PlainObject;
  if constexpr (Plain::RowsAtCompileTime == Eigen::Dynamic) {
    return m.derived();
  } else {
    return Plain(m);
  }
}

// The computations themselves, for a plain matrix type: called by spd_matrix.cpp at the kernels' sizes, and inline
// below at any other size.
template <typename Plain>
double smallest_eigenvalue_of(const Plain& a) {
  return Eigen::SelfAdjointEigenSolver<Plain>(a, Eigen::EigenvaluesOnly).eigenvalues().minCoeff();
}

template <typename Plain>
bool cholesky_certifies(const Plain& a) {
  const Eigen::LLT<Plain> llt(a);
  if (llt.info() != Eigen::Success) return false;
  const double floor = 1e-12 * a.diagonal().cwiseAbs().maxCoeff();
  return (llt.matrixLLT().diagonal().array().square() > floor).all();
}

template <typename Plain>
Plain floored(const Plain& a, double floor) {
  const Eigen::SelfAdjointEigenSolver<Plain> eig(symmetrized(a));
  return eig.eigenvectors() * eig.eigenvalues().cwiseMax(floor).asDiagonal() * eig.eigenvectors().transpose();
}
}  // namespace spd_detail

/// The smallest eigenvalue of the symmetric matrix m (its lower triangle is read).
template <typename Derived>
double smallest_eigenvalue(const Eigen::MatrixBase<Derived>& m) {
  using Plain = typename Derived::PlainObject;
  if constexpr (spd_detail::kernel_size<Plain>) {
    return spd_detail::smallest_eigenvalue(spd_detail::kernel_argument(m));
  } else {
    return spd_detail::smallest_eigenvalue_of(Plain(m));
  }
}

/// True when the Cholesky factorization of the symmetric m (lower triangle read) succeeds with every pivot above
/// 1e-12 of m's largest diagonal entry: m is then positive definite (in floating point a successful Cholesky
/// factorization certifies A + dA positive definite with |dA| <= c n u |A|: Higham, "Accuracy and Stability of
/// Numerical Algorithms", 2nd ed., Thm. 10.5), at a tenth of the cost of an eigenvalue decomposition.  False says
/// nothing: the matrix may still be positive definite but nearly singular (ask smallest_eigenvalue).
template <typename Derived>
bool cholesky_certifies_positive_definite(const Eigen::MatrixBase<Derived>& m) {
  using Plain = typename Derived::PlainObject;
  if constexpr (spd_detail::kernel_size<Plain>) {
    return spd_detail::cholesky_certifies_positive_definite(spd_detail::kernel_argument(m));
  } else {
    return spd_detail::cholesky_certifies(Plain(m));
  }
}

/// m equals its transpose to 1e-9 of max(1, largest |entry|) (rounding of a symmetric computation passes).
template <typename Derived>
bool is_symmetric(const Eigen::MatrixBase<Derived>& m) {
  if (m.size() == 0) return true;
  const double scale = std::max(1.0, m.cwiseAbs().maxCoeff());
  return (m - m.transpose()).cwiseAbs().maxCoeff() <= 1e-9 * scale;
}

/// What check_positive_definite found.
struct DefinitenessCheck {
  enum class Problem { kNone, kNotFinite, kNotSymmetric, kNotPositiveDefinite };
  Problem problem = Problem::kNone;
  double smallest_eigenvalue = 0;  ///< set when the matrix is finite and symmetric but not certified by Cholesky
  bool ok() const { return problem == Problem::kNone; }
};

/// The one positive-definiteness check of a stated covariance or information: finite, symmetric (is_symmetric), and
/// its smallest eigenvalue > 0.  A Cholesky factorization with clear pivots certifies the common case; only a
/// matrix it does not certify pays for the eigenvalues (whose smallest the caller's error message states).
template <typename Derived>
DefinitenessCheck check_positive_definite(const Eigen::MatrixBase<Derived>& m) {
  DefinitenessCheck c;
  if (!m.allFinite()) {
    c.problem = DefinitenessCheck::Problem::kNotFinite;
    return c;
  }
  if (!is_symmetric(m)) {
    c.problem = DefinitenessCheck::Problem::kNotSymmetric;
    return c;
  }
  if (m.size() > 0 && cholesky_certifies_positive_definite(m)) return c;
  c.smallest_eigenvalue = m.size() > 0 ? smallest_eigenvalue(m) : 0.0;
  if (!(c.smallest_eigenvalue > 0)) c.problem = DefinitenessCheck::Problem::kNotPositiveDefinite;
  return c;
}

template <typename Derived>
bool is_positive_definite(const Eigen::MatrixBase<Derived>& m) {
  return check_positive_definite(m).ok();
}

/// The one regularization of a derived covariance-like matrix: symmetrize, then floor the eigenvalues at `floor`.
/// With floor 0 this is the nearest positive semi-definite matrix in the Frobenius norm (Higham, "Computing a
/// nearest symmetric positive semidefinite matrix", Linear Algebra Appl. 103, 1988); with floor v > 0 every
/// eigenvalue is at least v, so the matrix is positive definite with its inverse bounded by 1/v.  Directions already
/// above the floor are left as they are.
template <typename Derived>
typename Derived::PlainObject floor_eigenvalues(const Eigen::MatrixBase<Derived>& m, double floor) {
  using Plain = typename Derived::PlainObject;
  if constexpr (spd_detail::kernel_size<Plain>) {
    return spd_detail::floor_eigenvalues(Plain(m), floor);
  } else {
    return spd_detail::floored(Plain(m), floor);
  }
}

}  // namespace sextant
