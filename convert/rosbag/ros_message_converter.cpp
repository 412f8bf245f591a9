// Compiled as C++17: ROS 1's generated message headers use std::allocator<void>::rebind, gone in C++20.
#include "convert/rosbag/ros_message_converter.hpp"

#include "estimators/lie/unit_quaternion.hpp"

#include <Eigen/Geometry>
#include <sextant/gnss_t.hpp>
#include <sextant/imu_t.hpp>
#include <sextant/odometry_t.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <stdexcept>
#include <vector>

namespace sextant::tools {
namespace {

constexpr const char* kSender = "sextant-convert";

int64_t utime(const ros::Time& t) { return static_cast<int64_t>(t.sec) * 1000000 + t.nsec / 1000; }

template <class A>
bool finite(const A& a) {
  return std::all_of(std::begin(a), std::end(a), [](double x) { return std::isfinite(x); });
}

template <size_t N, class A>
void copy(double (&dst)[N], const A& src) {
  std::copy(src.begin(), src.begin() + N, dst);
}

// ROS's pose covariance (about the parent frame's axes) -> sextant's right perturbation in the body frame.
void body_frame_pose_covariance(const Eigen::Quaterniond& q, const boost::array<double, 36>& ros, double (&out)[36]) {
  Eigen::Matrix<double, 6, 6> S = Eigen::Map<const Eigen::Matrix<double, 6, 6, Eigen::RowMajor>>(ros.data());
  Eigen::Matrix<double, 6, 6> Rt = Eigen::Matrix<double, 6, 6>::Zero();
  Rt.topLeftCorner<3, 3>() = Rt.bottomRightCorner<3, 3>() = q.toRotationMatrix().transpose();
  Eigen::Map<Eigen::Matrix<double, 6, 6, Eigen::RowMajor>> body(out);
  body = Rt * S * Rt.transpose();
}

constexpr const char* kCovarianceOverflows = "the pose covariance overflows when rotated into the body frame";

// Why the pose of `p` cannot be converted; nullptr when it can.
const char* pose_refused(const geometry_msgs::PoseWithCovariance& p) {
  const auto& o = p.pose.orientation;
  if (!std::isfinite(p.pose.position.x + p.pose.position.y + p.pose.position.z)) return "the position is not finite";
  if (!unit_quaternion(o.w, o.x, o.y, o.z)) return "the orientation quaternion is zero or not finite";
  if (!finite(p.covariance)) return "the pose covariance is not finite";
  return nullptr;
}

// The pose of `p` into `m`; false when the rotated covariance is not finite (entries near the largest double
// overflow when summed by the rotation).
bool set_pose(sextant::odometry_t& m, const geometry_msgs::PoseWithCovariance& p) {
  const auto& o = p.pose.orientation;
  const Eigen::Quaterniond q = *unit_quaternion(o.w, o.x, o.y, o.z);  // pose_refused said it spells one
  m.position[0] = p.pose.position.x, m.position[1] = p.pose.position.y, m.position[2] = p.pose.position.z;
  m.orientation[0] = q.w(), m.orientation[1] = q.x(), m.orientation[2] = q.y(), m.orientation[3] = q.z();
  body_frame_pose_covariance(q, p.covariance, m.covariance);
  return finite(m.covariance);
}

}  // namespace

std::string RosMessageConverter::channel(const std::string& topic, const char* fallback) const {
  const auto it = options_.channels.find(topic);
  return it == options_.channels.end() ? fallback : it->second;
}

std::string RosMessageConverter::body(const std::string& frame) const {
  const auto it = options_.bodies.find(frame);
  return it == options_.bodies.end() ? frame : it->second;
}

// Why it was not written (nullptr: written): a name (a frame_id) that holds a NUL byte: LCM's encoder ends a string at its first NUL, so the message
// would be shorter than its stated size and every reader would refuse it.
template <class Msg>
const char* RosMessageConverter::write(const std::string& channel, Msg& m) {
  m.sender = kSender;
  m.seq = seq_[channel];
  std::vector<uint8_t> bytes(static_cast<size_t>(m.getEncodedSize()));
  const int n = m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  if (n < 0) throw std::runtime_error("cannot encode a message for channel " + channel);
  if (static_cast<size_t>(n) != bytes.size()) return "a name (frame_id) holds a NUL byte";
  ++seq_[channel];
  sink_(m.utime, channel, bytes);
  ++result_.written[channel];
  return nullptr;
}

void RosMessageConverter::dropped(const std::string& topic, const ros::Time& stamp, const char* why) {
  ++result_.dropped[topic];
  char when[32];
  std::snprintf(when, sizeof when, "%u.%09u", stamp.sec, stamp.nsec);
  result_.first_dropped.try_emplace(topic, "topic " + topic + ", message stamped " + when + " s: " + why);
}

void RosMessageConverter::convert(const std::string& topic, const sensor_msgs::Imu& msg) {
  if (const char* why = write_imu(topic, msg)) dropped(topic, msg.header.stamp, why);
}
void RosMessageConverter::convert(const std::string& topic, const nav_msgs::Odometry& msg) {
  if (const char* why = write_odometry(topic, msg)) dropped(topic, msg.header.stamp, why);
}
void RosMessageConverter::convert(const std::string& topic, const sensor_msgs::NavSatFix& msg) {
  if (const char* why = write_fix(topic, msg)) dropped(topic, msg.header.stamp, why);
}
void RosMessageConverter::convert(const std::string& topic, const geometry_msgs::PoseWithCovarianceStamped& msg) {
  if (const char* why = write_pose(topic, msg)) dropped(topic, msg.header.stamp, why);
}

// A group ROS marks as not provided is written as zeros (an identity orientation), whatever its fields hold.
const char* RosMessageConverter::write_imu(const std::string& topic, const sensor_msgs::Imu& r) {
  sextant::imu_t m{};
  m.utime = utime(r.header.stamp);
  m.source = body(r.header.frame_id);
  m.frame = r.header.frame_id;
  m.has_angular_velocity = r.angular_velocity_covariance[0] != -1;
  m.has_linear_acceleration = r.linear_acceleration_covariance[0] != -1;
  const auto& q = r.orientation;
  m.has_orientation = r.orientation_covariance[0] != -1 && (q.w != 0 || q.x != 0 || q.y != 0 || q.z != 0);
  m.orientation_has_yaw = options_.yaw_free_topics.count(topic) == 0;
  m.orientation[0] = 1;
  if (m.has_angular_velocity) {
    const auto& w = r.angular_velocity;
    m.angular_velocity[0] = w.x, m.angular_velocity[1] = w.y, m.angular_velocity[2] = w.z;
    copy(m.angular_velocity_covariance, r.angular_velocity_covariance);
  }
  if (m.has_linear_acceleration) {
    const auto& a = r.linear_acceleration;
    m.linear_acceleration[0] = a.x, m.linear_acceleration[1] = a.y, m.linear_acceleration[2] = a.z;
    copy(m.linear_acceleration_covariance, r.linear_acceleration_covariance);
  }
  if (m.has_orientation) {
    // As the odometry's (unit_quaternion); one that spells no rotation drops the message, and the first such says
    // where.
    const auto u = unit_quaternion(q.w, q.x, q.y, q.z);
    if (!u) return "the orientation quaternion is zero or not finite";
    m.orientation[0] = u->w(), m.orientation[1] = u->x(), m.orientation[2] = u->y(), m.orientation[3] = u->z();
    copy(m.orientation_covariance, r.orientation_covariance);
  }
  if (!finite(m.angular_velocity) || !finite(m.angular_velocity_covariance))
    return "the angular velocity is not finite";
  if (!finite(m.linear_acceleration) || !finite(m.linear_acceleration_covariance))
    return "the linear acceleration is not finite";
  if (!finite(m.orientation_covariance)) return "the orientation covariance is not finite";
  return write(channel(topic, "IMU"), m);
}

const char* RosMessageConverter::write_odometry(const std::string& topic, const nav_msgs::Odometry& r) {
  if (const char* why = pose_refused(r.pose)) return why;
  sextant::odometry_t m{};
  m.utime = utime(r.header.stamp);
  m.source = body(r.child_frame_id.empty() ? r.header.frame_id : r.child_frame_id);
  if (!set_pose(m, r.pose)) return kCovarianceOverflows;
  const auto& t = r.twist.twist;
  m.linear_velocity[0] = t.linear.x, m.linear_velocity[1] = t.linear.y, m.linear_velocity[2] = t.linear.z;
  m.angular_velocity[0] = t.angular.x, m.angular_velocity[1] = t.angular.y, m.angular_velocity[2] = t.angular.z;
  copy(m.twist_covariance, r.twist.covariance);
  m.has_twist = finite(m.linear_velocity) && finite(m.angular_velocity) && finite(m.twist_covariance);
  if (!m.has_twist) return "the twist is not finite";
  return write(channel(topic, "ODOMETRY"), m);
}

const char* RosMessageConverter::write_pose(const std::string& topic,
                                            const geometry_msgs::PoseWithCovarianceStamped& r) {
  if (const char* why = pose_refused(r.pose)) return why;
  sextant::odometry_t m{};
  m.utime = utime(r.header.stamp);
  m.source = body(r.header.frame_id);
  if (!set_pose(m, r.pose)) return kCovarianceOverflows;
  return write(channel(topic, "ODOMETRY"), m);
}

const char* RosMessageConverter::write_fix(const std::string& topic, const sensor_msgs::NavSatFix& r) {
  sextant::gnss_t m{};
  m.utime = utime(r.header.stamp);
  m.source = body(r.header.frame_id);
  m.frame = r.header.frame_id;
  m.status = r.status.status;
  m.covariance_type = static_cast<int8_t>(r.position_covariance_type);
  if (m.status >= sextant::gnss_t::STATUS_FIX) {
    if (!std::isfinite(r.latitude) || !std::isfinite(r.longitude) || !std::isfinite(r.altitude) ||
        !finite(r.position_covariance))
      return "a fix with a non-finite position or covariance";
    m.latitude = r.latitude, m.longitude = r.longitude, m.altitude = r.altitude;
    copy(m.position_covariance, r.position_covariance);
  }
  return write(channel(topic, "GNSS"), m);
}

}  // namespace sextant::tools
