#pragma once
// ROS messages -> sextant's, one message at a time (the mapping: rosbag_converter.hpp).  Apart from the bag so that
// the same code converts what ROS's bag library deserialized (read_rosbag) and what a fuzz harness deserialized
// from arbitrary bytes.  C++17 only: ROS 1's generated message headers do not compile as C++20.
#include "convert/rosbag/rosbag_converter.hpp"

#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <nav_msgs/Odometry.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/NavSatFix.h>

#include <cstdint>
#include <map>
#include <string>

namespace sextant::tools {

/// Converts ROS messages into sextant's and hands each to the sink; counts what it writes and drops in `result`.
class RosMessageConverter {
 public:
  RosMessageConverter(const RosbagConversionOptions& options, const RosbagSink& sink, RosbagConversion& result)
      : options_(options), sink_(sink), result_(result) {}

  /// `msg`, received on `topic`, onto the topic's channel (from `options.channels`, else IMU, ODOMETRY or GNSS by
  /// type); a message with a non-finite value where one is required, or a frame_id with a NUL byte, is counted in
  /// `dropped` instead (the first of each topic described in `first_dropped`).
  void convert(const std::string& topic, const sensor_msgs::Imu& msg);
  void convert(const std::string& topic, const nav_msgs::Odometry& msg);
  void convert(const std::string& topic, const sensor_msgs::NavSatFix& msg);
  void convert(const std::string& topic, const geometry_msgs::PoseWithCovarianceStamped& msg);

 private:
  std::string channel(const std::string& topic, const char* fallback) const;
  std::string body(const std::string& frame) const;
  template <class Msg>
  const char* write(const std::string& channel, Msg& m);
  /// Counts a message dropped on `topic`; the first one's stamp and `why` go to RosbagConversion::first_dropped.
  void dropped(const std::string& topic, const ros::Time& stamp, const char* why);
  // Each writes the message and returns nullptr, or returns why it was not written.
  const char* write_imu(const std::string& topic, const sensor_msgs::Imu& r);
  const char* write_odometry(const std::string& topic, const nav_msgs::Odometry& r);
  const char* write_fix(const std::string& topic, const sensor_msgs::NavSatFix& r);
  const char* write_pose(const std::string& topic, const geometry_msgs::PoseWithCovarianceStamped& r);

  const RosbagConversionOptions& options_;
  const RosbagSink& sink_;
  RosbagConversion& result_;
  std::map<std::string, int64_t> seq_;  // per channel
};

}  // namespace sextant::tools
