#pragma once
// FUSED_POSE "inertial_graph": for every body that carries an IMU, the fixed-lag keyframe smoother of
// estimators/inertial (inertial_smoother.hpp: IMU preintegration between keyframes, the wheel odometry's increments,
// robust GNSS antenna positions with the lever arm, gravity in the model, the biases estimated, the oldest keyframe
// marginalized), on (config key engine.inertial.graph.enabled) beside the inertial filter, sharing its section:
// mountings, IMU noise, the GNSS datum and plane, publish_rate_hz.
//
// A body starts at its first odometry message after an IMU sample with rates and acceleration: orientation as the
// filter's (the unit's own, or roll and pitch from gravity with yaw 0), velocity the odometry's twist when it has
// one, position the origin.  Its first GNSS fix places it: the smoother restarts at its current state moved to the fix
// (less the lever arm), as the filter's anchor.  A body whose start yaw is not ENU (engine.inertial.gnss_heading, as
// the filter's) adds no fix to the smoother until its track against the fixes gives the heading
// (estimators/inertial/gnss_heading.hpp); the smoother then restarts in ENU with the alignment's position and yaw
// sigmas as its prior (gnss_realign.hpp).  Status: gnss_heading_waiting, gnss_heading_aligned.  A planar odometry source's increments constrain x, y and yaw only
// (z as x and y: a ground robot does not move along its own z axis; roll and pitch 0.1 rad per increment); a GNSS component that engine.inertial.gnss_position does
// not select gets a variance of 1e8 m^2 (no information).
// Outputs at most publish_rate_hz per body (data time): the state predicted to the last IMU sample, with the newest
// keyframe's marginal covariance (recomputed at each keyframe) over sextant's right perturbation [rho; phi] (both in
// the body frame, fused_pose_t's convention, as every estimator publishes).  Counters: keyframes, fixes down-weighted by the robust kernel, dropped input, failed solves, and how
// many bodies have their tilt and their yaw observable (the smoother's test on the newest keyframe).
#include "daemon/engine/inertial_inputs.hpp"
#include "daemon/engine/inertial_stage_config.hpp"
#include "daemon/engine/stage.hpp"
#include "estimators/geodesy/local_tangent_plane.hpp"
#include "estimators/inertial/inertial_smoother.hpp"

#include <map>
#include <optional>
#include <string>

namespace sextant::engine {

class InertialGraphStage final : public Stage {
 public:
  /// Throws std::invalid_argument for a mounting that is not a rotation, or options out of range.
  explicit InertialGraphStage(InertialConfig config);

  StageKind kind() const override { return StageKind::kInertialGraph; }
  std::optional<PrimaryEstimator> estimator_kind() const override { return PrimaryEstimator::kInertialGraph; }
  bool accepts(const Event& e) const override;
  void handle(const Event& e, const Emit& emit) override;
  void forget(const std::string& source) override { bodies_.erase(source); }
  Counters counters() const override;

 private:
  struct Body {
    std::optional<inertial::InertialSmoother> smoother;  // from the first odometry message after an IMU sample
    std::optional<ImuSample> first_imu;                  // the sample the start takes its orientation from
    int64_t t0 = 0;                                      // utime of the smoother's time 0
    int64_t last_published = 0, keyframes = 0;
    std::optional<SE3> last_odometry;
    Matrix6 last_odometry_covariance = Matrix6::Zero();
    std::optional<geodesy::LocalTangentPlane> plane;
    bool anchored = false;
    bool yaw_known = true;                                  // the start's yaw is ENU
    std::optional<inertial::GnssHeadingAlignment> heading;  // from the first fix until the heading is known
    Matrix6 covariance = Matrix6::Identity();  // the newest keyframe's, over the right perturbation [rho; phi]
    inertial::Observability observability;
  };

  double seconds(const Body& b, int64_t utime) const { return static_cast<double>(utime - b.t0) * 1e-6; }
  void on_imu(const ImuSample& s, const Emit& emit);
  void on_odometry(const Odometry& o);
  void on_gnss(const GnssFix& g);
  void start(Body& b, const Odometry& o);
  /// The first fix: the smoother restarts at its current state with the body under the antenna.
  void anchor(Body& b, double t, const Eigen::Vector3d& antenna, const Eigen::Vector3d& lever);
  /// A fix at t while the heading is not known (the filter stage's wait_for_heading, for the smoother).
  void wait_for_heading(Body& b, double t, const Eigen::Vector3d& antenna, const Eigen::Matrix3d& R,
                        const Eigen::Vector3d& lever);
  /// After a keyframe: the newest pose's covariance and observability.
  void refresh(Body& b);
  void publish(const std::string& source, Body& b, int64_t utime, const Emit& emit);

  InertialConfig config_;
  inertial::InertialSmootherOptions options_;
  SensorMountings mountings_;
  std::map<std::string, Body> bodies_;
  int64_t unmounted_ = 0, started_ = 0, anchored_ = 0, published_ = 0, heading_aligned_ = 0;
};

}  // namespace sextant::engine
