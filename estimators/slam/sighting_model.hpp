#pragma once
// A landmark sighting as a keyframe-relative observation, and its gate against the current estimate.
//
// A sighting is taken at an odometry time, not at a keyframe's: it is anchored on the newest keyframe K at or before
// it (keyframe_track.hpp, anchor_at) with the odometry D from K to the sighting, so its factor is on K with the sensor
// offset D S (S the sensor in the body), h = range/bearing (planar) or range/azimuth/elevation (3-D) of the landmark
// in that sensor frame (graph::PointObservationFactor), and the odometry's uncertainty folded into the measurement's:
//     R' = R + J_D Sigma_D J_D',    J_D = dh/dD (right perturbation of X_K D, which is one of D).
// Several sightings in one odometry interval share D's error but enter as independent (slightly optimistic).
// The gate of a sighting of a known landmark: d2 = e' S^-1 e with
//     S = R + k^2 J_D Sigma_D J_D' + J_K P_K J_K' + J_p P_p J_p',   J_K = J_D Ad(D^-1)   (X_K Exp(xi) D = X_K D Exp(Ad(D^-1) xi)),
// P the marginal covariances of keyframe and landmark, their correlation ignored (S larger for a landmark mapped from
// the same poses), accepted when d2 <= chi2_n(p), n = 2 (planar) or 3.
// A landmark's first sighting initializes it at X_K D S l(z) and is not gated.
#include "estimators/graph/factor.hpp"
#include "estimators/lie/se3.hpp"
#include "estimators/slam/keyframe_track.hpp"
#include "estimators/slam/slam_inputs.hpp"

#include <Eigen/Core>

#include <vector>

namespace sextant::slam {

/// The sightings of one message, anchored at `anchor` on a keyframe whose estimate is `keyframe_pose`.
class SightingModel {
 public:
  SightingModel(bool planar, const SE3& keyframe_pose, const TrackPoint& anchor, const SE3& sensor_in_body);

  /// The measurement dimension n: 2 (range, bearing) planar, 3 (range, azimuth, elevation) 3-D.
  int dimension() const { return planar_ ? 2 : 3; }
  graph::PointObservationFactor::Model model() const;
  /// The sighting's measurement z and covariance R (n of each); false when malformed: a non-finite value, a range
  /// that is not positive or an R that is not positive definite (spd_matrix.hpp's check).
  bool measurement(const LandmarkSighting& s, Eigen::VectorXd& z, Eigen::MatrixXd& R) const;
  /// Where the sighting puts the landmark, X_K D S l(z) (z = 0 on a planar body).
  Eigen::Vector3d landmark_from(const LandmarkSighting& s) const;

  /// The sighting's residual e = h - z at a landmark position, its Jacobians, and the odometry's part of R'.
  struct Evaluation {
    Eigen::VectorXd error;
    Eigen::MatrixXd d_motion;       // J_D = dh/dD (n x 3 planar, n x 6)
    Eigen::MatrixXd d_landmark;     // J_p (n x 2 planar, n x 3)
    Eigen::MatrixXd odometry_part;  // J_D Sigma_D J_D'
  };
  Evaluation evaluate(const Eigen::VectorXd& z, const Eigen::Vector3d& landmark) const;
  /// The gate's d2 (see above): `keyframe_marginal` / `landmark_marginal` empty when not determined (left out).
  double mahalanobis(const Evaluation& ev, const Eigen::MatrixXd& R, double odometry_scale,
                     const Eigen::MatrixXd& landmark_marginal, const Eigen::MatrixXd& keyframe_marginal) const;
  /// The information of the factor, (R + J_D Sigma_D J_D')^-1, symmetrized.
  Eigen::MatrixXd information(const Evaluation& ev, const Eigen::MatrixXd& R) const;
  /// The sensor at the sighting in the keyframe's frame, D S: the factor's sensor offset.
  const SE3& sensor_in_keyframe() const { return sensor_in_keyframe_; }

 private:
  bool planar_;
  SE3 sensor_in_body_, sensor_in_keyframe_, at_sighting_;
  Eigen::MatrixXd sigma_d_, ad_;
  mutable std::vector<graph::Variable> local_;
};

}  // namespace sextant::slam
