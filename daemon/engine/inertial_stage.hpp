#pragma once
// FUSED_POSE "inertial": for every body that carries an IMU, the error-state filter of estimators/inertial
// (error_state_ekf.hpp, with late measurements placed in time by lagged_eskf.hpp) driven by the IMU and corrected
// by what robot_localization's users fuse:
//  - IMU (imu_t): angular velocity and specific force predict (both needed); the unit's own orientation updates
//    roll, pitch and, when the unit gives one, yaw (engine.inertial.imu_orientation selects the fields);
//  - wheel odometry (odometry_t's twist): the body velocity in the odometry message's body frame
//    (engine.inertial.odometry_velocity selects vx, vy, vz);
//  - GNSS (gnss_t): the antenna's position in an East-North-Up tangent plane at the datum (configured, or the body's
//    first fix), with the antenna's lever arm, behind a chi-square gate; optionally its velocity.  The body's first
//    fix places it (its position becomes the fix's, less the lever arm).
// Each sensor's mounting (rotation and lever arm) is looked up by (body, frame) in engine.inertial.mountings; a
// sample of a frame without one is refused and counted (`unmounted`).  The filter starts at a body's first IMU sample
// that has both rates and acceleration: roll and pitch from the unit's orientation when it has one, else from gravity
// in the specific force (the body at rest), yaw from the unit's orientation when it has a yaw, else 0.
// Heading (engine.inertial.gnss_heading): a body whose yaw is not ENU (a yaw-free unit, none, or align: always) is
// placed at its first fix but fuses no fix until its dead-reckoned track against the fixes gives the frame's heading
// (estimators/inertial/gnss_heading.hpp, over baseline_m); its state and covariance then move into ENU
// (gnss_realign.hpp) and fixes are gated and fused from the next one.  Status: gnss_heading_waiting (bodies waiting)
// and gnss_heading_aligned (alignments).  After gnss_heading.reacquire_after consecutive gated fixes (the estimate
// has left the fixes and the gate would refuse every later one) the body waits for its heading again
// (gnss_heading_reacquired).
// Frames: the world frame is the filter's: ENU at the datum when GNSS is fused (once the heading is known), else the
// frame the first orientation gives.  Outputs at most engine.inertial.publish_rate_hz per body (data time), pose and
// 6x6 covariance over sextant's right perturbation (fused_pose_t: translation and rotation in the body frame; the
// filter's position error, in the world frame, rotated into the body: right_perturbation_from_world_position).
#include "daemon/engine/inertial_inputs.hpp"
#include "daemon/engine/inertial_stage_config.hpp"
#include "daemon/engine/stage.hpp"
#include "estimators/geodesy/local_tangent_plane.hpp"
#include "estimators/inertial/lagged_eskf.hpp"

#include <map>
#include <memory>
#include <optional>
#include <string>

namespace sextant::engine {

class InertialStage final : public Stage {
 public:
  /// Throws std::invalid_argument for a mounting that is not a rotation or not finite.
  explicit InertialStage(InertialConfig config);

  StageKind kind() const override { return StageKind::kInertial; }
  std::optional<PrimaryEstimator> estimator_kind() const override { return PrimaryEstimator::kInertial; }
  bool accepts(const Event& e) const override;
  void handle(const Event& e, const Emit& emit) override;
  void forget(const std::string& source) override { bodies_.erase(source); }
  Counters counters() const override;

 private:
  struct Body {
    std::unique_ptr<inertial::LaggedEskf> filter;  // null until the first IMU sample with rates and acceleration
    int64_t t0 = 0;                                // utime of the filter's time 0 (seconds are relative to it)
    int64_t last_published = 0;
    std::optional<geodesy::LocalTangentPlane> plane;
    bool yaw_known = true;                                  // the start's yaw is ENU
    std::optional<inertial::GnssHeadingAlignment> heading;  // from the first fix until the heading is known
    int consecutive_gated = 0;                              // fixes refused by the gate in a row
  };

  const inertial::SensorMounting* mounting(const std::string& source, const std::string& frame) const;
  double seconds(const Body& b, int64_t utime) const { return static_cast<double>(utime - b.t0) * 1e-6; }
  void on_imu(const ImuSample& s, const Emit& emit);
  void start(Body& b, const ImuSample& s, const inertial::SensorMounting& m);
  void on_odometry(const Odometry& o);
  void on_gnss(const GnssFix& g);
  /// The body's first fix: its position becomes the antenna's, less the lever arm, with the fix's covariance (the
  /// filter's frame becomes the ENU plane; whatever it held of the position before is dropped).
  void anchor(Body& b, const Eigen::Vector3d& antenna, const Eigen::Matrix3d& R, const Eigen::Vector3d& lever);
  /// A fix while the heading is not known: the antenna's dead-reckoned position at the fix's time t (the filter's
  /// state extrapolated with its velocity) against the fix; once they give the heading, the filter moves into ENU.
  void wait_for_heading(Body& b, double t, const Eigen::Vector3d& antenna, const Eigen::Matrix3d& R,
                        const Eigen::Vector3d& lever);
  /// Counts a fix's position update; after reacquire_after gated in a row the body waits for its heading again.
  void count_fix(Body& b, const filter::UpdateResult& r);
  /// Counts the outcome of an update by its reason.
  void count(const filter::UpdateResult& r);
  void publish(const std::string& source, Body& b, int64_t utime, const Emit& emit);

  InertialConfig config_;
  inertial::EskfOptions options_;
  SensorMountings mountings_;
  std::map<std::string, Body> bodies_;
  int64_t imu_ = 0, started_ = 0, unmounted_ = 0, imu_refused_ = 0, updates_ = 0, refused_ = 0, gated_ = 0,
          too_old_ = 0, published_ = 0, no_filter_yet_ = 0, anchored_ = 0, heading_aligned_ = 0, reacquired_ = 0;
};

}  // namespace sextant::engine
