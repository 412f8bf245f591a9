#pragma once
// Whether an estimate may be kept and published: every number finite, and a covariance that is a covariance.
// Every estimator checks its state with this after a step and, when the step made it unhealthy, restores the state
// from before the step and counts the refusal by its reason: one hostile input never leaves a body corrupted.
//
// What is checked, and what it costs (n = state dimension):
//   - x and P all finite: O(n^2), the order of the step itself;
//   - P symmetric within 1e-9 of its largest entry, and every diagonal entry >= 0: O(n^2);
//   - the leading `block` x `block` block (the robot's pose) positive semi-definite, its smallest eigenvalue
//     >= -1e-9 * its largest magnitude: O(block^3).
// The whole of a large SLAM covariance is not eigen-decomposed on every step (O(n^3)); its landmark blocks are
// checked through the diagonal, and the Joseph-form updates keep them positive semi-definite under rounding.
#include <Eigen/Core>

#include <algorithm>
#include <cmath>

namespace sextant::filter {

enum class Health {
  kHealthy,
  kNonFinite,   // a NaN or an infinity in the state or its covariance
  kIndefinite,  // the covariance is not symmetric positive semi-definite (a negative variance, or worse)
};

/// "healthy", "non_finite", "indefinite": the counter keys estimators report refusals under.
inline const char* health_name(Health h) {
  switch (h) {
    case Health::kHealthy:
      return "healthy";
    case Health::kNonFinite:
      return "non_finite";
    case Health::kIndefinite:
      return "indefinite";
  }
  return "unknown";
}

/// The health of the symmetric pose block B: positive semi-definite to rounding (its smallest eigenvalue >= -1e-9 *
/// its largest magnitude).  Out of line (estimate_health.cpp): Eigen's eigenvalue solver is compiled once.
Health pose_block_health(const Eigen::MatrixXd& B);

/// The health of a symmetric matrix used as a covariance (the checks above, with `block` its leading block).
template <class M>
Health covariance_health(const M& P, Eigen::Index block) {
  if (!P.allFinite()) return Health::kNonFinite;
  if (P.rows() != P.cols()) return Health::kIndefinite;
  if (P.size() == 0) return Health::kHealthy;
  const double scale = P.cwiseAbs().maxCoeff();
  if ((P - P.transpose()).cwiseAbs().maxCoeff() > 1e-9 * std::max(scale, 1.0)) return Health::kIndefinite;
  if ((P.diagonal().array() < 0).any()) return Health::kIndefinite;
  const Eigen::Index k = std::min(block, P.rows());
  return pose_block_health(P.topLeftCorner(k, k));
}

/// The health of an estimate x with covariance P (the robot's pose first, `block` components).
template <class V, class M>
Health estimate_health(const V& x, const M& P, Eigen::Index block) {
  if (!x.allFinite()) return Health::kNonFinite;
  return covariance_health(P, block);
}

}  // namespace sextant::filter

namespace sextant::filter {

/// Steps an estimator refused because of what they would have done to its estimate, by reason (counters
/// "refused_non_finite" and "refused_indefinite" on the status channel).
struct Refusals {
  int64_t non_finite = 0, indefinite = 0;
  void count(Health h) {
    if (h == Health::kNonFinite)
      ++non_finite;
    else if (h == Health::kIndefinite)
      ++indefinite;
  }
  Refusals& operator+=(const Refusals& o) {
    non_finite += o.non_finite, indefinite += o.indefinite;
    return *this;
  }
};

}  // namespace sextant::filter
