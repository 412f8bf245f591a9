#include "daemon/engine/inertial_inputs.hpp"

namespace sextant::engine {

SensorMountings::SensorMountings(const std::vector<SensorMountingConfig>& configs) {
  for (const auto& c : configs) {
    const auto m = inertial::SensorMounting::from_xyz_rpy({c.xyz[0], c.xyz[1], c.xyz[2]}, c.rpy[0], c.rpy[1], c.rpy[2]);
    m.check(("engine.inertial.mountings: frame " + c.frame).c_str());
    table_[{c.source, c.frame}] = m;
  }
}

const inertial::SensorMounting* SensorMountings::find(const std::string& source, const std::string& frame) const {
  if (auto it = table_.find({source, frame}); it != table_.end()) return &it->second;
  if (auto it = table_.find({"", frame}); it != table_.end()) return &it->second;
  return nullptr;
}

Eigen::Matrix3d stated_or_default(const Eigen::Matrix3d& stated, double variance) {
  return stated.isZero(0) ? Eigen::Matrix3d(Eigen::Matrix3d::Identity() * variance) : stated;
}

bool yaw_known_in_enu(const InertialConfig& c, const ImuSample& s) {
  switch (c.gnss_heading.align) {
    case GnssHeadingConfig::Align::kAlways:
      return false;
    case GnssHeadingConfig::Align::kNever:
      return true;
    case GnssHeadingConfig::Align::kAuto:
      break;
  }
  return s.orientation && s.orientation_has_yaw && c.imu_orientation[2];
}

inertial::GnssHeadingOptions gnss_heading_options(const InertialConfig& c) {
  inertial::GnssHeadingOptions o;
  o.baseline_m = c.gnss_heading.baseline_m;
  o.min_inlier_fraction = c.gnss_heading.min_inlier_fraction;
  return o;
}

Eigen::Quaterniond initial_orientation(const ImuSample& s, const inertial::SensorMounting& m,
                                       const inertial::BodyImuSample& body) {
  if (s.orientation) return Eigen::Quaterniond(s.orientation->toRotationMatrix() * m.rotation.transpose()).normalized();
  const Eigen::Vector3d up = body.accel.normalized();  // the world's z in the body frame
  return Eigen::Quaterniond::FromTwoVectors(up, Eigen::Vector3d::UnitZ());
}

}  // namespace sextant::engine
