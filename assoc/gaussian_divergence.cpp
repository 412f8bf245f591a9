#include "assoc/gaussian_divergence.hpp"

#include <Eigen/Cholesky>

#include <cmath>
#include <limits>

namespace sextant::assoc {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// log|S| by Cholesky; nullopt-like -inf when S is not positive definite.
bool log_det(const Eigen::MatrixXd& S, double& out) {
  const Eigen::LLT<Eigen::MatrixXd> llt(S);
  if (llt.info() != Eigen::Success) return false;
  out = 2 * llt.matrixL().toDenseMatrix().diagonal().array().log().sum();
  return std::isfinite(out);
}

}  // namespace

double renyi_divergence(const Eigen::VectorXd& mu1, const Eigen::MatrixXd& S1, const Eigen::VectorXd& mu2,
                        const Eigen::MatrixXd& S2, double alpha) {
  if (!(alpha > 0 && alpha < 1)) return kInf;
  const Eigen::MatrixXd Sa = alpha * S2 + (1 - alpha) * S1;
  double l1, l2, la;
  if (!log_det(S1, l1) || !log_det(S2, l2) || !log_det(Sa, la)) return kInf;
  const Eigen::VectorXd d = mu1 - mu2;
  const double maha = d.dot(Sa.llt().solve(d));
  return alpha / 2 * maha - (la - (1 - alpha) * l1 - alpha * l2) / (2 * (alpha - 1));
}

double kl_divergence(const Eigen::VectorXd& mu1, const Eigen::MatrixXd& S1, const Eigen::VectorXd& mu2,
                     const Eigen::MatrixXd& S2) {
  double l1, l2;
  if (!log_det(S1, l1) || !log_det(S2, l2)) return kInf;
  const Eigen::LLT<Eigen::MatrixXd> llt(S2);
  const Eigen::VectorXd d = mu1 - mu2;
  return 0.5 * ((llt.solve(S1)).trace() + d.dot(llt.solve(d)) - static_cast<double>(mu1.size()) + l2 - l1);
}

double symmetric_kl_divergence(const Eigen::VectorXd& mu1, const Eigen::MatrixXd& S1, const Eigen::VectorXd& mu2,
                               const Eigen::MatrixXd& S2) {
  return 0.5 * (kl_divergence(mu1, S1, mu2, S2) + kl_divergence(mu2, S2, mu1, S1));
}

double symmetric_renyi_divergence(const Eigen::VectorXd& mu1, const Eigen::MatrixXd& S1, const Eigen::VectorXd& mu2,
                                  const Eigen::MatrixXd& S2, double alpha) {
  return 0.5 * (renyi_divergence(mu1, S1, mu2, S2, alpha) + renyi_divergence(mu2, S2, mu1, S1, alpha));
}

}  // namespace sextant::assoc
