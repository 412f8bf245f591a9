#include "estimators/filter/kalman_update.hpp"

#include "estimators/filter/estimate_health.hpp"
#include "estimators/kind_names.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <utility>

namespace sextant::filter {
namespace {
constexpr std::pair<UpdateReason, const char*> kUpdateReasons[] = {{UpdateReason::kNone, "none"},
                                                                   {UpdateReason::kNewLandmark, "new_landmark"},
                                                                   {UpdateReason::kGate, "gate"},
                                                                   {UpdateReason::kNonFinite, "non_finite"},
                                                                   {UpdateReason::kSingular, "singular"},
                                                                   {UpdateReason::kNoComponents, "no_components"},
                                                                   {UpdateReason::kNoTwist, "no_twist"},
                                                                   {UpdateReason::kUnknownLandmark, "unknown_landmark"},
                                                                   {UpdateReason::kMapFull, "map_full"},
                                                                   {UpdateReason::kTooOld, "too_old"},
                                                                   {UpdateReason::kIndefinite, "indefinite"}};
}  // namespace

const char* update_reason_name(UpdateReason reason) { return kind_name(kUpdateReasons, reason); }

namespace {

// The health of P - K C' - C K' computed before it is formed, in O(n m): its diagonal (every variance) and its
// leading pose block, from P's; an entry can only overflow where |K| |C| is huge.  P itself is healthy (every step
// that made it was checked).
Health joseph_health(const Eigen::MatrixXd& P, const Eigen::MatrixXd& K, const Eigen::MatrixXd& C) {
  if (!K.allFinite() || !C.allFinite()) return Health::kNonFinite;
  if (K.size() > 0 && K.cwiseAbs().maxCoeff() * C.cwiseAbs().maxCoeff() * static_cast<double>(K.cols()) > 1e300)
    return Health::kNonFinite;
  const Eigen::VectorXd diagonal = P.diagonal() - 2.0 * (K.cwiseProduct(C)).rowwise().sum();
  if (!diagonal.allFinite()) return Health::kNonFinite;
  if ((diagonal.array() < 0).any()) return Health::kIndefinite;
  const Eigen::Index b = std::min<Eigen::Index>(P.rows(), 6);
  const Eigen::MatrixXd block =
      P.topLeftCorner(b, b) - K.topRows(b) * C.topRows(b).transpose() - C.topRows(b) * K.topRows(b).transpose();
  return covariance_health(block, b);
}

}  // namespace

UpdateResult kalman_update(Eigen::VectorXd& x, Eigen::MatrixXd& P, const Eigen::VectorXd& r, const Eigen::MatrixXd& H,
                           const Eigen::MatrixXd& R, double gate) {
  if (!H.allFinite()) {
    UpdateResult out;
    out.reason = UpdateReason::kNonFinite;
    return out;
  }
  const Eigen::MatrixXd PHt = P * H.transpose();
  return kalman_update_from(x, P, r, PHt, H * PHt, R, gate);
}

UpdateResult kalman_update_from(Eigen::VectorXd& x, Eigen::MatrixXd& P, const Eigen::VectorXd& r,
                                const Eigen::MatrixXd& PHt, const Eigen::MatrixXd& HPHt, const Eigen::MatrixXd& R,
                                double gate) {
  UpdateResult out;
  if (!r.allFinite() || !PHt.allFinite() || !R.allFinite()) {
    out.reason = UpdateReason::kNonFinite;
    return out;
  }
  const Eigen::MatrixXd S = HPHt + R;
  const Eigen::LLT<Eigen::MatrixXd> llt(S);
  if (llt.info() != Eigen::Success) {
    out.reason = UpdateReason::kSingular;
    return out;
  }
  out.nis = r.dot(llt.solve(r));
  if (gate > 0 && out.nis > gate) {
    out.reason = UpdateReason::kGate;
    return out;
  }
  const Eigen::MatrixXd K = llt.solve(PHt.transpose()).transpose();  // P H' S^-1
  const Eigen::VectorXd dx = K * r;
  if (!dx.allFinite() || !(x + dx).allFinite()) {
    out.reason = UpdateReason::kNonFinite;
    return out;
  }
  // Joseph form (I - K H) P (I - K H)' + K R K', expanded so it costs O(n^2 m) instead of O(n^3):
  //   P - K (H P) - (H P)' K' + K S K'    with H P = (P H')' and S = H P H' + R
  //   = P - K C' - C K'  with C = P H' - K S / 2: a symmetric rank-2m update of the upper triangle, mirrored.
  const Eigen::MatrixXd C = PHt - 0.5 * K * S;
  if (const Health h = joseph_health(P, K, C); h != Health::kHealthy) {
    out.reason = h == Health::kNonFinite ? UpdateReason::kNonFinite : UpdateReason::kIndefinite;
    return out;
  }
  for (Eigen::Index k = 0; k < K.cols(); ++k) P.selfadjointView<Eigen::Upper>().rankUpdate(K.col(k), C.col(k), -1.0);
  P.triangularView<Eigen::StrictlyLower>() = P.transpose();
  x += dx;
  out.accepted = true;
  return out;
}

double chi2_gate_99(int dof) {
  static const double q[] = {6.635, 9.210, 11.345, 13.277, 15.086, 16.812};
  return q[std::clamp(dof, 1, 6) - 1];
}

}  // namespace sextant::filter
