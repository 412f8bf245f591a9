#pragma once
// The measurement update shared by every Kalman-type filter in sextant (Probabilistic Robotics, Table 3.1, with the EKF's
// Jacobian in place of C):
//   S = H P H' + R,  K = P H' S^-1,  x <- x + K r,  P <- (I - K H) P (I - K H)' + K R K'   (Joseph form)
// where r = z - h(x) is the innovation.  The Joseph form keeps P symmetric positive definite under rounding; it is
// evaluated in its expanded O(n^2) form, so an EKF-SLAM update with hundreds of landmarks stays cheap.
// Gating: the normalized innovation squared d2 = r' S^-1 r is compared with a chi-square threshold first.
#include <Eigen/Core>

#include <string>

namespace sextant::filter {

struct UpdateResult {
  bool accepted = false;
  double nis = 0;       // r' S^-1 r
  std::string reason;   // why it was refused: "gate", "non_finite", "singular"
};

/// Updates (x, P) in place unless the innovation fails the gate (`gate` <= 0 disables gating).
UpdateResult kalman_update(Eigen::VectorXd& x, Eigen::MatrixXd& P, const Eigen::VectorXd& innovation,
                           const Eigen::MatrixXd& H, const Eigen::MatrixXd& R, double gate);

/// The same update when P H' is already known (`PHt`, n x m) and H P H' too (`HPHt`): filters whose H is sparse
/// compute both in O(n) and skip the dense product.
UpdateResult kalman_update_from(Eigen::VectorXd& x, Eigen::MatrixXd& P, const Eigen::VectorXd& innovation,
                                const Eigen::MatrixXd& PHt, const Eigen::MatrixXd& HPHt, const Eigen::MatrixXd& R,
                                double gate);

/// The chi-square quantile for `dof` degrees of freedom at probability 0.99 (dof 1..6), for gates.
double chi2_gate_99(int dof);

}  // namespace sextant::filter
