#pragma once
// What the inertial stages (inertial_stage.hpp, inertial_graph_stage.hpp) share about their inputs: the sensors'
// mountings looked up by (body, frame), a stated covariance or the configured default, and a body's orientation at
// the start.
#include "daemon/engine/events.hpp"
#include "daemon/engine/inertial_stage_config.hpp"
#include "estimators/inertial/gnss_heading.hpp"
#include "estimators/inertial/sensor_mounting.hpp"

#include <map>
#include <string>
#include <utility>
#include <vector>

namespace sextant::engine {

/// engine.inertial.mountings, checked: a mounting for a frame of one body, or of every body ("").
class SensorMountings {
 public:
  /// Throws std::invalid_argument naming the frame of a mounting that is not a rotation or not finite.
  explicit SensorMountings(const std::vector<SensorMountingConfig>& configs);
  /// The body's own mounting of `frame`, else every body's, else null.
  const inertial::SensorMounting* find(const std::string& source, const std::string& frame) const;

 private:
  std::map<std::pair<std::string, std::string>, inertial::SensorMounting> table_;
};

/// `stated`, or variance * I where the message states none (all zeros).
Eigen::Matrix3d stated_or_default(const Eigen::Matrix3d& stated, double variance);

/// Whether a body whose filter starts with sample `s` has its yaw in East-North-Up (engine.inertial.gnss_heading.align:
/// kAuto: the unit states a yaw and imu_orientation fuses it).
bool yaw_known_in_enu(const InertialConfig& c, const ImuSample& s);

/// The heading alignment's options from engine.inertial.gnss_heading.
inertial::GnssHeadingOptions gnss_heading_options(const InertialConfig& c);

/// The body's orientation at the start from an IMU sample at mounting m (`body` its sample moved to the body): the
/// unit's own orientation when it has one, else roll and pitch from gravity in the specific force (f = R^T (a - g)
/// at rest: f points up in the body frame), yaw 0.
Eigen::Quaterniond initial_orientation(const ImuSample& s, const inertial::SensorMounting& m,
                                       const inertial::BodyImuSample& body);

}  // namespace sextant::engine
