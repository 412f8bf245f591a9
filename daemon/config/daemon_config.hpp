#pragma once
// sextantd's configuration: the runtime (bus, queues, status, recording), channel names and the engine's stages.
// `load_daemon_config` parses a YAML file (config/default.yaml documents every key) and validates it; any error
// is a ConfigError whose message starts with FILE:LINE:COLUMN.
#include "daemon/config/config_reader.hpp"
#include "daemon/engine/engine_config.hpp"

#include <string>

namespace sextant::config {

struct Channels {
  std::string prefix;  // prepended to every channel below (one daemon per robot: "ROBOT1_")
  std::string odometry = "ODOMETRY";
  std::string landmarks = "LANDMARKS";
  std::string bearings = "BEARINGS";
  std::string loop_closures = "LOOP_CLOSURES";
  std::string imu = "IMU";
  std::string gnss = "GNSS";
  std::string fused_pose = "FUSED_POSE";
  std::string fused_geo = "FUSED_GEO";  // geo_pose_t: the poses of estimators anchored at a GNSS datum, on the Earth
  std::string trajectory = "TRAJECTORY";
  std::string targets = "TARGETS";
  std::string match_requests = "MATCH_REQUESTS";
  std::string landmark_map = "LANDMARK_MAP";
  std::string status = "SEXTANT_STATUS";
  // The fleet's channels (engine.graph.fleet.exchange): shared by every daemon of the fleet, so without the prefix.
  std::string fleet = "FLEET";
  std::string fleet_control = "FLEET_CONTROL";

  std::string full(const std::string& name) const { return prefix + name; }
};

/// Plausibility by physics (daemon/runtime/plausibility.hpp): what a decoded, finite input may still not say.  A
/// message outside these bounds is refused at intake and counted by reason; the defaults fit robots, drones and
/// aircraft on or near the Earth, and each says what it costs a legitimate sender.
struct Plausibility {
  double max_position_m = 1.0e8;  // any position, sensor position or loop translation: |p| <= this (15 Earth radii)
  double max_speed_planar_mps = 50.0;     // a planar (ground) body's odometry: |dp| <= speed * dt + max_jump_m
  double max_speed_spatial_mps = 350.0;   // a 3-D body's (an airliner's cruise speed)
  double max_jump_m = 1.0;                // what an odometry position may jump beyond its speed (noise, a small reset)
  double max_planar_tilt_rad = 0.1;       // planar messages: roll/pitch above this are refused; below, projected away
  double max_range_m = 1.0e5;             // a landmark sighting's range
  double min_variance = 1.0e-12;          // every covariance's smallest eigenvalue (its meaningful block) >= this
  double max_variance = 1.0e12;           // ... its largest <= this (a loop's information: the inverses)
  double max_condition = 1.0e12;          // ... and their ratio <= this (beyond, updates cancel every digit)
  double max_angular_rate_radps = 100.0;  // an IMU's |angular velocity| (consumer gyroscopes saturate near 35 rad/s)
  double max_acceleration_mps2 = 1000.0;  // an IMU's |specific force| (about 100 g)
};

struct DaemonConfig {
  std::string name = "sextantd";      // sender name in every published message
  std::string lcm_url;                // empty: LCM's default (LCM_DEFAULT_URL or udpm://239.255.76.67:7667)
  double status_period_s = 1.0;       // SEXTANT_STATUS period
  int queue_capacity = 1024;          // events per stage queue; a full queue drops (and counts) new events
  int publish_queue_capacity = 4096;  // outputs waiting for the publisher thread
  std::string record;                 // record every received message to this LCM log ("" = off)
  double log_rate_limit_s = 1.0;      // at most one warning per channel and reason per this many seconds
  double max_ahead_s = 60.0;          // the time guard (daemon/runtime/time_order_guard.hpp)
  int time_resync_messages = 5;
  double max_ahead_of_wall_s = 60.0;
  int max_sources = 256;              // bodies and sensors tracked
  double source_idle_s = 0;           // forget a silent source after this long (0: never)
  double source_evict_idle_s = 60.0;  // live, table full: a source silent this long may give its place (0: never)
  double drain_timeout_s = 5.0;       // SIGTERM: how long stage queues may drain
  std::string state_dir;              // state directory (README "State directory"; "" = off); --state-dir overrides
  double state_period_s = 10.0;       // wall-clock seconds between two saves of the state (and one at shutdown)
  bool discard_bad_state = false;     // --discard-bad-state: set a bad state file aside and start fresh
  uint64_t engine_fingerprint = 0;    // of the parsed engine config (state files of another config are refused)
  Plausibility plausibility;          // daemon.plausibility
  double source_handover_s = 2.0;     // a stream's second sender is refused until its first is silent this long
  Channels channels;
  engine::EngineConfig engine;
};

/// The fingerprint of a parsed engine config, by its values (aggregate_fields.hpp): the same whether a default is
/// written or left out; the state directory refuses a state saved under another.
uint64_t engine_fingerprint(const engine::EngineConfig& engine);
/// A config file's largest size (a documented config is a few kilobytes): read in bounded memory and time.
inline constexpr size_t kMaxConfigBytes = 1 << 20;
/// Parses and validates a YAML config file: only a regular file, at most kMaxConfigBytes, one YAML document, no
/// control characters, no key written twice in one section.
DaemonConfig load_daemon_config(const std::string& path);
/// The same from YAML text (`file` names it in errors).
DaemonConfig parse_daemon_config(const std::string& yaml_text, const std::string& file);

/// Reads the engine section (every stage's block); used by sextantd and `sextant replay`.
void read_engine_config(Section& section, engine::EngineConfig& config);

}  // namespace sextant::config
