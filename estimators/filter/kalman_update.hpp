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

/// How an update ended when it was not a plain accepted one: why it was refused, or that it added a landmark.
enum class UpdateReason {
  kNone,             // accepted: an update of what the state holds
  kNewLandmark,      // accepted: the landmark joined the state (landmark_admission.hpp)
  kGate,             // refused: the innovation failed the gate
  kNonFinite,        // refused: a NaN or infinity in the innovation, Jacobian or noise
  kSingular,         // refused: S is not positive definite
  kNoComponents,     // refused: no component of the measurement is fused
  kNoTwist,          // refused: velocities to fuse but no twist in the message or its predecessor
  kUnknownLandmark,  // refused: a landmark the state does not hold and may not add (not SLAM, or no id)
  kMapFull,          // refused: the state holds max_landmarks already
  kTooOld,           // refused: stamped before the filter's history (inertial/lagged_eskf.hpp)
  kIndefinite,       // refused: the update would leave the covariance indefinite (estimate_health.hpp); undone
};
/// The reason's spelling for counters and logs: "none", "new_landmark", "gate", "non_finite", "singular",
/// "no_components", "no_twist", "unknown_landmark", "map_full", "too_old", "indefinite".
const char* update_reason_name(UpdateReason reason);

struct UpdateResult {
  bool accepted = false;
  double nis = 0;  // r' S^-1 r
  UpdateReason reason = UpdateReason::kNone;
};

/// Updates (x, P) in place unless the innovation fails the gate (`gate` <= 0 disables gating).  An update whose
/// result would not be finite, or whose covariance would have a negative variance (estimate_health.hpp; e.g. a
/// noise of 1e300 beside one of 1e-3 cancels every digit), is undone: (x, P) are left as they were and the reason
/// is kNonFinite or kIndefinite.
UpdateResult kalman_update(Eigen::VectorXd& x, Eigen::MatrixXd& P, const Eigen::VectorXd& innovation,
                           const Eigen::MatrixXd& H, const Eigen::MatrixXd& R, double gate);

/// The same update when P H' is already known (`PHt`, n x m) and H P H' too (`HPHt`): filters whose H is sparse
/// compute both in O(n) and skip the dense product.
UpdateResult kalman_update_from(Eigen::VectorXd& x, Eigen::MatrixXd& P, const Eigen::VectorXd& innovation,
                                const Eigen::MatrixXd& PHt, const Eigen::MatrixXd& HPHt, const Eigen::MatrixXd& R,
                                double gate);

/// The work the updates of one batch of measurements may still cost, in floating-point operations: an update (or a
/// landmark added) of a state of size n costs about 8 n^2 (the Joseph form's rank-2m update, m = 2, and its
/// checks).  The first update of a batch is always allowed, so that a large map still learns from every batch.
class UpdateBudget {
 public:
  explicit UpdateBudget(double flops) : left_(flops) {}
  /// Whether one more update of a state of size n fits; charges it when it does.
  bool spend(Eigen::Index n) {
    const double cost = 8.0 * static_cast<double>(n) * static_cast<double>(n);
    if (used_ && cost > left_) return false;
    left_ -= cost;
    used_ = true;
    return true;
  }

 private:
  double left_;
  bool used_ = false;
};

/// The chi-square quantile for `dof` degrees of freedom at probability 0.99 (dof 1..6), for gates.
double chi2_gate_99(int dof);

}  // namespace sextant::filter
