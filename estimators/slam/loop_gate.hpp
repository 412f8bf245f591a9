#pragma once
// Loop closures onto keyframes and their consistency gate against the current estimate.
//
// A loop z = T_from^-1 T_to between two times whose ends land on keyframes through odometry motions D_from, D_to
// (keyframe_track.hpp, resolve) becomes a loop between the keyframes,
//     z' = D_from z D_to^-1 = T_kf_from^-1 T_kf_to,
// and when an end carries a covariance (a thinned keyframe's edge) that covariance is added to the loop's own,
// Sigma' = Omega^-1 + Sigma_D_from + Sigma_D_to (both in the loop's frame; over x, y, yaw for a planar body).
//
// The gate: e = Log(z'^-1 X_from^-1 X_to) (X the current estimates), d2 = e' S^-1 e with
//     S = Omega'^-1 + k^2 P_path,
// P_path the odometry's covariance between the two keyframes (KeyframeTrack::odometry_path): an upper bound of the
// estimate's relative uncertainty, so a true loop passes with the gate's probability however far the odometry
// drifted, as long as the odometry's covariance is honest; k (loop_gate_odometry_scale) covers the biases real
// odometry does not report.  The loop is accepted when d2 <= chi2_d(p), d = 3 (planar) or 6.
//
// A loop whose ends land through thinned keyframes far from its times (with lifelong thinning the keyframe before a
// thinned one can be minutes of odometry away) is uncertain by that odometry's drift: with a standard deviation of
// sigma metres there, the gate passes any error up to sqrt(chi2_d(p)) sigma, so a match to another place passes
// as easily as a true one, and the loop's information is small anyway.  landing_sigma measures it; a loop above
// SlamOptions::loop_max_landing_sigma is refused before the gate.
#include "estimators/lie/se3.hpp"
#include "estimators/slam/keyframe_track.hpp"

namespace sextant::slam {

/// A loop moved onto keyframes: its measurement z' and information Omega' (6x6; a planar body's at x, y, yaw).
struct KeyframeLoop {
  SE3 z;
  Matrix6d information = Matrix6d::Zero();
  bool widened = false;  // an end's covariance was added (it landed through a thinned keyframe)
};

/// The loop `relative` (T_from^-1 T_to, information `information`) with its ends at `from` and `to`.
KeyframeLoop loop_on_keyframes(bool planar, const SE3& relative, const Matrix6d& information, const TrackPoint& from,
                               const TrackPoint& to);

/// How far off the loop's ends may be where they land: the largest standard deviation (m) of the translation that
/// the ends' covariances add, sqrt(lambda_max) of the x, y, z block of Sigma_D_from + Sigma_D_to.  0 when both
/// ends are keyframes' own times.
double landing_sigma(const TrackPoint& from, const TrackPoint& to);

/// d2 of the loop against the predicted relative pose X_from^-1 X_to, with the odometry path covariance scaled by
/// odometry_scale^2 (see above).
double loop_mahalanobis(bool planar, const KeyframeLoop& loop, const SE3& predicted, const Matrix6d& path_covariance,
                        double odometry_scale);

}  // namespace sextant::slam
