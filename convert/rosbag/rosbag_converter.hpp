#pragma once
// ROS 1 bags -> an LCM log of sextant's messages, read with ROS's own bag library (Debian's rosbag_storage), so
// every bag version, compression (bz2, lz4) and chunk layout ROS writes is read as ROS reads it.
//
// Messages (by type; other types are counted and skipped):
//  - sensor_msgs/Imu -> imu_t: angular velocity, linear acceleration (gravity included, as ROS's Imu carries it),
//    orientation, with their covariances; a group whose covariance[0] is -1 (ROS's "not provided") has has_* false,
//    and so has an orientation whose quaternion is all zeros; such a group is written as zeros (the orientation as
//    the identity), whatever its fields held.  orientation_has_yaw unless the topic is listed in `yaw_free_topics`.
//    The orientation is normalized (as the odometry's: a driver's rounding off unit length is not carried into the
//    log); one with a non-finite component makes the message dropped, and the first such is described in
//    `first_dropped` (topic and stamp).
//  - nav_msgs/Odometry -> odometry_t: pose (position, orientation) and twist (linear, angular, in child_frame_id) with
//    their covariances.  ROS's pose covariance is about the axes of header.frame_id; sextant's is the right
//    perturbation in the body frame, so it is rotated: Sigma = diag(R^T, R^T) Sigma_ros diag(R, R).  The twist's
//    covariance is in the body frame in both.
//  - geometry_msgs/PoseWithCovarianceStamped -> odometry_t with the pose only (has_twist false), the same rotation.
//  - sensor_msgs/NavSatFix -> gnss_t: status (NavSatStatus's values; a NO_FIX message's NaN coordinates become 0),
//    latitude, longitude, altitude, the ENU position covariance and its type.
// Times: utime = header.stamp; the log keeps the bag's order (receive time) and stamps each event with its utime.
// Names: `channels` maps a topic to its channel (when non-empty, only the listed topics are converted); other
// topics go to IMU, ODOMETRY or GNSS by type.  `bodies` maps a frame_id (the Odometry's child_frame_id, the header's
// frame_id otherwise) to the body name in `source`; an unmapped frame is its own body name.  imu_t.frame and
// gnss_t.frame keep the ROS frame_id (the mounting is looked up by it).
// A message with a non-finite value where one is required (a stamp, a fix's coordinates, a pose) is counted and
// dropped (so is a pose whose covariance, rotated into the body frame, overflows, and a frame_id with a NUL byte,
// which an LCM string cannot hold).
#include <cstdint>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace sextant::tools {

struct RosbagConversionOptions {
  std::map<std::string, std::string> channels;  // topic -> channel
  std::map<std::string, std::string> bodies;    // ROS frame_id -> body (source)
  std::set<std::string> yaw_free_topics;        // IMU topics whose orientation has no meaningful yaw
};

struct RosbagConversion {
  std::map<std::string, int64_t> written;  // per channel
  std::map<std::string, int64_t> skipped;  // per topic: types sextant does not take, or topics not listed
  std::map<std::string, int64_t> dropped;  // per topic: non-finite values
  /// Per topic, the first message dropped for a reason found in a value, and why ("topic /imu, message stamped
  /// 12.500000000 s: the orientation quaternion is zero or not finite").
  std::map<std::string, std::string> first_dropped;
};

/// Receives each converted message: its utime, channel and lcm-gen encoding.
using RosbagSink = std::function<void(int64_t utime, const std::string& channel, const std::vector<uint8_t>& bytes)>;

/// Reads the bag and hands each converted message to `sink`, in the bag's order.  Throws std::runtime_error naming
/// the bag when it cannot be read or a message record is shorter than its type (with ROS's own message).
RosbagConversion read_rosbag(const std::string& bag, const RosbagConversionOptions& options, const RosbagSink& sink);

/// read_rosbag into an LCM log (each event stamped with the message's utime); also throws when `out_lcm` cannot be
/// written.
RosbagConversion convert_rosbag(const std::string& bag, const std::string& out_lcm,
                                const RosbagConversionOptions& options = {});

}  // namespace sextant::tools
