#pragma once
// Closed-form divergences between Gaussian densities N1 = N(mu1, S1) and N2 = N(mu2, S2) in k dimensions
// (Gil, Alajaji & Linder, "Renyi divergence measures for commonly used univariate continuous distributions",
// Information Sciences 249, 2013):
//   Renyi, order alpha in (0, 1):  S_a = alpha S2 + (1 - alpha) S1,
//     D_a(N1||N2) = alpha/2 dmu' S_a^-1 dmu - 1/(2 (alpha - 1)) ln( |S_a| / (|S1|^(1-alpha) |S2|^alpha) )
//   Kullback-Leibler (the alpha -> 1 limit):
//     KL(N1||N2) = 1/2 [ tr(S2^-1 S1) + dmu' S2^-1 dmu - k + ln(|S2| / |S1|) ]
//   Symmetric Renyi (the passive-association paper's eq. 19-21, see tuple_costs.hpp):
//     SD_a = 1/2 (D_a(N1||N2) + D_a(N2||N1)).
//   Symmetric KL, the same symmetrization at alpha -> 1 (half Jeffreys' divergence):
//     SKL = 1/2 (KL(N1||N2) + KL(N2||N1)) = 1/4 [ tr(S2^-1 S1) + tr(S1^-1 S2) - 2k + dmu' (S1^-1 + S2^-1) dmu ]
//     (equal to 1/2 dmu' S^-1 dmu when the covariances are equal, as the classic cost's term).
// With equal covariances D_a = alpha/2 dmu' S^-1 dmu, so sextant's association cost scales the divergence by 1/alpha
// to make it equal 1/2 dmu' S^-1 dmu there (a divergence cost then equals the classic cost when the covariances
// are equal).
#include <Eigen/Core>

namespace sextant::assoc {

/// +infinity when a covariance is not positive definite or alpha is outside (0, 1).
double renyi_divergence(const Eigen::VectorXd& mu1, const Eigen::MatrixXd& S1, const Eigen::VectorXd& mu2,
                        const Eigen::MatrixXd& S2, double alpha);
double kl_divergence(const Eigen::VectorXd& mu1, const Eigen::MatrixXd& S1, const Eigen::VectorXd& mu2,
                     const Eigen::MatrixXd& S2);
double symmetric_kl_divergence(const Eigen::VectorXd& mu1, const Eigen::MatrixXd& S1, const Eigen::VectorXd& mu2,
                               const Eigen::MatrixXd& S2);
double symmetric_renyi_divergence(const Eigen::VectorXd& mu1, const Eigen::MatrixXd& S1, const Eigen::VectorXd& mu2,
                                  const Eigen::MatrixXd& S2, double alpha);

}  // namespace sextant::assoc
