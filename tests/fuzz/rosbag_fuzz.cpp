// Fuzz harness: what sextant does with the messages of a ROS 1 bag.  ROS's bag library parses the bag itself, and
// deserializes each message record as the harness does here (ros::serialization over the record's bytes); sextant's
// own code is the conversion of the deserialized Imu, Odometry, NavSatFix and PoseWithCovarianceStamped.  The first
// byte picks the type, the second the options (a yaw-free topic, a channel map, a body map), the rest is the
// message as ROS serializes it.  Contract checked: every message written decodes as its sextant type with every
// number finite (a non-finite one is dropped and counted, never written, and the first drop says why), and every
// quaternion written (the odometry's, the IMU's) is unit.
// Compiled as C++17 (ROS 1's message headers).
#include "convert/rosbag/ros_message_converter.hpp"

#include <sextant/gnss_t.hpp>
#include <sextant/imu_t.hpp>
#include <sextant/odometry_t.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <iterator>
#include <vector>

using namespace sextant;

namespace {

template <class A>
bool finite(const A& a) {
  return std::all_of(std::begin(a), std::end(a), [](double x) { return std::isfinite(x); });
}

template <class Msg>
Msg decoded(const std::vector<uint8_t>& bytes) {
  Msg m;
  if (m.decode(bytes.data(), 0, static_cast<int>(bytes.size())) != static_cast<int>(bytes.size())) std::abort();
  return m;
}

bool unit(const double (&q)[4]) { return std::abs(std::hypot(std::hypot(q[0], q[1]), q[2], q[3]) - 1) < 1e-9; }

bool sound(const imu_t& m) {
  return finite(m.angular_velocity) && finite(m.angular_velocity_covariance) && finite(m.linear_acceleration) &&
         finite(m.linear_acceleration_covariance) && finite(m.orientation) && finite(m.orientation_covariance) &&
         unit(m.orientation);
}

bool sound(const odometry_t& m) {
  return finite(m.position) && finite(m.orientation) && unit(m.orientation) && finite(m.covariance) &&
         finite(m.increment_covariance) && finite(m.linear_velocity) && finite(m.angular_velocity) &&
         finite(m.twist_covariance);
}

bool sound(const gnss_t& m) {
  return std::isfinite(m.latitude) && std::isfinite(m.longitude) && std::isfinite(m.altitude) &&
         finite(m.position_covariance) && finite(m.velocity) && finite(m.velocity_covariance) &&
         std::isfinite(m.heading) && std::isfinite(m.heading_variance);
}

// Deserializes `bytes` as Ros (as rosbag's instantiate does) and converts it; checks what is written as Sextant.
template <class Ros, class Sextant>
void run(std::vector<uint8_t> bytes, const tools::RosbagConversionOptions& options) {
  // Every type is longer than nothing; and ROS's stream would do arithmetic on the null data() of an empty vector,
  // which the bag reader never hands it.
  if (bytes.empty()) return;
  Ros msg;
  try {
    ros::serialization::IStream s(bytes.data(), static_cast<uint32_t>(bytes.size()));
    ros::serialization::deserialize(s, msg);
  } catch (const ros::serialization::StreamOverrunException&) {
    return;  // too short for the type: the bag reader reports it
  }
  tools::RosbagConversion result;
  const tools::RosbagSink sink = [](int64_t, const std::string&, const std::vector<uint8_t>& b) {
    if (!sound(decoded<Sextant>(b))) std::abort();
  };
  tools::RosMessageConverter(options, sink, result).convert("/topic", msg);
  if (result.dropped.size() != result.first_dropped.size()) std::abort();  // every drop says why
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 2) return 0;
  tools::RosbagConversionOptions options;
  if (data[1] & 1) options.yaw_free_topics.insert("/topic");
  if (data[1] & 2) options.channels["/topic"] = "MAPPED";
  if (data[1] & 4) options.bodies["base_link"] = "robot";
  std::vector<uint8_t> bytes(data + 2, data + size);
  switch (data[0] % 4) {
    case 0:
      run<sensor_msgs::Imu, imu_t>(std::move(bytes), options);
      break;
    case 1:
      run<nav_msgs::Odometry, odometry_t>(std::move(bytes), options);
      break;
    case 2:
      run<sensor_msgs::NavSatFix, gnss_t>(std::move(bytes), options);
      break;
    default:
      run<geometry_msgs::PoseWithCovarianceStamped, odometry_t>(std::move(bytes), options);
      break;
  }
  return 0;
}
