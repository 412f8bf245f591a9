// Compiled as C++17: ROS 1's generated message headers use std::allocator<void>::rebind, gone in C++20.
#include "convert/rosbag/ros_message_converter.hpp"
#include "convert/rosbag/rosbag_converter.hpp"

#include <rosbag/bag.h>
#include <rosbag/view.h>

#include <stdexcept>

namespace sextant::tools {
namespace {

// The message of type Ros in `mi` through `convert`; false when it is of another type.
template <class Ros>
bool try_convert(RosMessageConverter& convert, const rosbag::MessageInstance& mi) {
  const auto msg = mi.instantiate<Ros>();
  if (!msg) return false;
  convert.convert(mi.getTopic(), *msg);
  return true;
}

}  // namespace

RosbagConversion read_rosbag(const std::string& bag_path, const RosbagConversionOptions& options,
                             const RosbagSink& sink) {
  rosbag::Bag bag;
  try {
    bag.open(bag_path, rosbag::bagmode::Read);
  } catch (const std::exception& e) {
    throw std::runtime_error(bag_path + ": " + e.what());
  }
  RosbagConversion result;
  RosMessageConverter convert(options, sink, result);
  try {
    for (const rosbag::MessageInstance& mi : rosbag::View(bag)) {
      if (!options.channels.empty() && options.channels.count(mi.getTopic()) == 0) {
        ++result.skipped[mi.getTopic()];
        continue;
      }
      const bool taken = try_convert<sensor_msgs::Imu>(convert, mi) || try_convert<nav_msgs::Odometry>(convert, mi) ||
                         try_convert<sensor_msgs::NavSatFix>(convert, mi) ||
                         try_convert<geometry_msgs::PoseWithCovarianceStamped>(convert, mi);
      if (!taken) ++result.skipped[mi.getTopic()];
    }
  } catch (const ros::Exception& e) {
    // The bag's own errors (BagException) and a message record shorter than its type (StreamOverrunException).
    throw std::runtime_error(bag_path + ": " + e.what());
  }
  return result;
}

}  // namespace sextant::tools
