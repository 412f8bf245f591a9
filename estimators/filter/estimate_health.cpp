#include "estimators/filter/estimate_health.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>

namespace sextant::filter {

Health pose_block_health(const Eigen::MatrixXd& B) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(B, Eigen::EigenvaluesOnly);
  if (eig.info() != Eigen::Success) return Health::kNonFinite;
  if (eig.eigenvalues().minCoeff() < -1e-9 * std::max(B.cwiseAbs().maxCoeff(), 1e-300)) return Health::kIndefinite;
  return Health::kHealthy;
}

}  // namespace sextant::filter
