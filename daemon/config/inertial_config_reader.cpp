#include "daemon/config/stage_config_readers.hpp"
#include "estimators/inertial/sensor_mounting.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace sextant::config {
namespace {

// A list of component names -> which of three are fused, e.g. [roll, pitch] of {roll, pitch, yaw}.
void read_fields(Section& s, const std::string& key, const std::array<const char*, 3>& names,
                 std::array<bool, 3>& out) {
  std::vector<std::string> listed;
  s.get(key, listed);
  if (!s.node().IsMap()) return;  // no section: the defaults
  const YAML::Node node = s.node()[key];
  if (!node.IsDefined()) return;
  out.fill(false);
  for (const auto& f : listed) {
    const auto at = std::find_if(names.begin(), names.end(), [&](const char* n) { return f == n; });
    if (at == names.end())
      throw s.error_at(node, "'" + s.path() + "." + key + "': unknown component '" + f + "' (" + names[0] + ", " +
                                 names[1] + ", " + names[2] + ")");
    out[static_cast<size_t>(at - names.begin())] = true;
  }
}

// mountings: {FRAME: {body: NAME (default: every body), xyz: [x, y, z], rpy: [roll, pitch, yaw]}}
void read_mountings(Section& s, engine::InertialConfig& c) {
  Section list = s.child("mountings");
  if (!list.node().IsDefined() || list.node().IsNull()) return;
  if (!list.node().IsMap()) throw list.error("'" + list.path() + "': expected a map of sensor frame -> mounting");
  for (const YAML::Node& key : list.keys()) {
    engine::SensorMountingConfig m;
    m.frame = key.Scalar();
    Section e = list.child(m.frame);
    e.get("body", m.source);
    std::vector<double> xyz{0, 0, 0}, rpy{0, 0, 0};
    const auto three = Check<std::vector<double>>([](const std::vector<double>& v) -> std::optional<std::string> {
      if (v.size() != 3) return "expected 3 numbers";
      for (double x : v)
        if (!std::isfinite(x)) return "not finite";
      return std::nullopt;
    });
    e.get("xyz", xyz, three);
    e.get("rpy", rpy, three);
    e.reject_unknown_keys();
    std::copy(xyz.begin(), xyz.end(), m.xyz.begin());
    std::copy(rpy.begin(), rpy.end(), m.rpy.begin());
    try {
      inertial::SensorMounting::from_xyz_rpy({xyz[0], xyz[1], xyz[2]}, rpy[0], rpy[1], rpy[2]).check(m.frame.c_str());
    } catch (const std::invalid_argument& ex) {
      throw e.error(std::string("'") + e.path() + "': " + ex.what());
    }
    c.mountings.push_back(m);
  }
}

void read_graph(Section& s, engine::InertialGraphConfig& c) {
  s.get("enabled", c.enabled);
  s.get("keyframe_interval", c.keyframe_interval, in_range(0.01, 60));
  s.get("window", c.window, int_in_range(2, 1000));
  s.get("gnss_kernel_width", c.gnss_kernel_width, positive());
  s.get("initial_yaw_sigma", c.initial_yaw_sigma, positive());
  s.reject_unknown_keys();
}

void read_gnss_heading(Section& s, engine::GnssHeadingConfig& c) {
  using Align = engine::GnssHeadingConfig::Align;
  std::string align = c.align == Align::kAlways ? "always" : c.align == Align::kNever ? "never" : "auto";
  s.get("align", align, one_of({"auto", "always", "never"}));
  c.align = align == "always" ? Align::kAlways : align == "never" ? Align::kNever : Align::kAuto;
  s.get("baseline_m", c.baseline_m, in_range(1, 1e4));
  s.get("min_inlier_fraction", c.min_inlier_fraction, in_range(0.01, 1));
  s.get("reacquire_after", c.reacquire_after, int_in_range(0, 100000));
  s.reject_unknown_keys();
}

}  // namespace

void read_stage_config(Section& s, engine::InertialConfig& c) {
  s.get("enabled", c.enabled);
  read_mountings(s, c);
  s.get("gyro_noise_density", c.gyro_noise_density, positive());
  s.get("accel_noise_density", c.accel_noise_density, positive());
  s.get("gyro_bias_random_walk", c.gyro_bias_random_walk, non_negative());
  s.get("accel_bias_random_walk", c.accel_bias_random_walk, non_negative());
  read_fields(s, "imu_orientation", {"roll", "pitch", "yaw"}, c.imu_orientation);
  read_fields(s, "odometry_velocity", {"vx", "vy", "vz"}, c.odometry_velocity);
  read_fields(s, "gnss_position", {"east", "north", "up"}, c.gnss_position);
  read_fields(s, "gnss_velocity", {"east", "north", "up"}, c.gnss_velocity);
  s.get("default_orientation_variance", c.default_orientation_variance, positive());
  s.get("default_velocity_variance", c.default_velocity_variance, positive());
  s.get("default_gnss_variance", c.default_gnss_variance, positive());
  s.get("gnss_gate", c.gnss_gate, non_negative());
  s.get("history_s", c.history_s, in_range(0, 60));
  s.get("publish_rate_hz", c.publish_rate_hz, in_range(0.1, 10000));
  s.get("initial_sigma_gyro_bias", c.initial_sigma_gyro_bias, positive());
  s.get("initial_sigma_accel_bias", c.initial_sigma_accel_bias, positive());
  s.get("datum", c.datum, Check<std::vector<double>>([](const std::vector<double>& v) -> std::optional<std::string> {
          if (v.empty()) return std::nullopt;
          if (v.size() != 3) return "expected [latitude, longitude, altitude] or []";
          if (!(std::abs(v[0]) <= 90) || !(std::abs(v[1]) <= 180) || !(std::abs(v[2]) <= 1e5))
            return "latitude in [-90, 90], longitude in [-180, 180], altitude within 100 km";
          return std::nullopt;
        }));
  Section heading = s.child("gnss_heading");
  read_gnss_heading(heading, c.gnss_heading);
  Section graph = s.child("graph");
  read_graph(graph, c.graph);
  s.reject_unknown_keys();
}

}  // namespace sextant::config
