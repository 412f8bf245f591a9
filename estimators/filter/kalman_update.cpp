#include "estimators/filter/kalman_update.hpp"

#include <Eigen/Cholesky>

#include <algorithm>

namespace sextant::filter {

UpdateResult kalman_update(Eigen::VectorXd& x, Eigen::MatrixXd& P, const Eigen::VectorXd& r, const Eigen::MatrixXd& H,
                           const Eigen::MatrixXd& R, double gate) {
  UpdateResult out;
  if (!r.allFinite() || !H.allFinite() || !R.allFinite()) {
    out.reason = "non_finite";
    return out;
  }
  const Eigen::MatrixXd PHt = P * H.transpose();
  const Eigen::MatrixXd S = H * PHt + R;
  const Eigen::LLT<Eigen::MatrixXd> llt(S);
  if (llt.info() != Eigen::Success) {
    out.reason = "singular";
    return out;
  }
  out.nis = r.dot(llt.solve(r));
  if (gate > 0 && out.nis > gate) {
    out.reason = "gate";
    return out;
  }
  const Eigen::MatrixXd K = llt.solve(PHt.transpose()).transpose();  // P H' S^-1
  x += K * r;
  const Eigen::MatrixXd IKH = Eigen::MatrixXd::Identity(P.rows(), P.cols()) - K * H;
  P = IKH * P * IKH.transpose() + K * R * K.transpose();
  P = (0.5 * (P + P.transpose())).eval();  // .eval(): an in-place transpose would alias
  out.accepted = true;
  return out;
}

double chi2_gate_99(int dof) {
  static const double q[] = {6.635, 9.210, 11.345, 13.277, 15.086, 16.812};
  return q[std::clamp(dof, 1, 6) - 1];
}

}  // namespace sextant::filter
