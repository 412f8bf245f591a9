#pragma once
// The engine as the value fuzzer drives it (the test in test_hostile_values.cpp and the libFuzzer harness
// tests/fuzz/values_fuzz.cpp): simulated runs as the bus carries them, an intake and every stage of the default
// configuration fed their bytes, what is published checked, and the mutations that put extreme but finite values
// into the inputs' fields.  Where a choice is made (which field, which value) it comes from a `Choose`: a seeded
// generator in the test, the fuzzer's bytes in the harness.
#include "daemon/config/daemon_config.hpp"
#include "daemon/engine/engine.hpp"
#include "daemon/engine/guarded_handle.hpp"
#include "daemon/runtime/intake.hpp"
#include "daemon/runtime/lcm_log.hpp"
#include "estimators/filter/estimate_health.hpp"
#include "sim/simulator.hpp"

#include <sextant/gnss_t.hpp>
#include <sextant/imu_t.hpp>
#include <sextant/landmarks_t.hpp>
#include <sextant/loop_closure_t.hpp>
#include <sextant/odometry_t.hpp>

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace sextant::hostile {

struct Record {
  std::string channel;
  std::vector<uint8_t> bytes;
};

/// A simulated planar run of `source` as the bus would carry it (its odometry, sightings and bearings).  The
/// simulator's loop closures need poses 20 s old, so a short run has none; `loops`: a closure about every second
/// instead, to a pose within 6 m and at least 2 s back.  `inertial`: its IMU (100 Hz, frame "imu") and GNSS (5 Hz,
/// frame "gnss") too.
inline std::vector<Record> simulated_run(const std::string& source, double duration_s, uint64_t seed,
                                         bool unknown_ids = false, bool loops = false, bool inertial = false) {
  tools::SimulationOptions sim;
  sim.duration_s = duration_s;
  sim.seed = seed;
  sim.source = source;
  if (inertial) sim.imu_rate_hz = 100, sim.gnss_rate_hz = 5;
  sim.unknown_ids = unknown_ids;
  if (loops) sim.loop_distance = 6, sim.loop_min_age_s = 2;
  const auto path = (std::filesystem::temp_directory_path() /
                     ("sextant_hostile_" + std::to_string(::getpid()) + "_" + source + ".lcm"))
                        .string();
  {
    runtime::LogWriter w(path);
    tools::simulate(sim, w);
  }
  std::vector<Record> out;
  for (auto& r : runtime::LogReader::read_all(path))
    if (r.channel != "GROUND_TRUTH") out.push_back({r.channel, std::vector<uint8_t>(r.data.begin(), r.data.end())});
  std::filesystem::remove(path);
  return out;
}

inline runtime::InputKind kind_of(const std::string& channel) {
  if (channel == "ODOMETRY") return runtime::InputKind::kOdometry;
  if (channel == "LANDMARKS") return runtime::InputKind::kLandmarks;
  if (channel == "BEARINGS") return runtime::InputKind::kBearings;
  if (channel == "IMU") return runtime::InputKind::kImu;
  if (channel == "GNSS") return runtime::InputKind::kGnss;
  return runtime::InputKind::kLoopClosures;
}

/// A published pose is finite with a positive semi-definite covariance.
inline bool healthy(const engine::FusedPose& p) {
  Eigen::Matrix<double, 7, 1> x;
  x << p.pose.position, p.pose.orientation.coeffs();
  return filter::estimate_health(x, p.covariance, 6) == filter::Health::kHealthy && x.allFinite();
}

/// A published pose on the Earth is finite, on it, with a positive semi-definite covariance.
inline bool healthy(const engine::GeoPose& g) {
  return std::isfinite(g.latitude) && std::abs(g.latitude) <= 90 && std::isfinite(g.longitude) &&
         std::isfinite(g.altitude) && g.orientation.coeffs().allFinite() &&
         filter::estimate_health(Eigen::Vector3d(g.latitude, g.longitude, g.altitude), g.position_covariance, 3) ==
             filter::Health::kHealthy;
}

/// The engine of config/default.yaml's defaults (a particle filter in place of the EKF when `pf`; with `inertial`,
/// the inertial filter and smoother too, for sensors mounted as "imu" and "gnss") behind an intake, fed one bus
/// message at a time; keeps what it publishes and the longest event.
struct Run {
  config::DaemonConfig cfg;
  runtime::ChannelStats stats;
  std::unique_ptr<runtime::Intake> intake;
  std::unique_ptr<engine::Engine> engine;
  std::vector<engine::FusedPose> poses;
  int geo_poses = 0;
  double max_event_ms = 0;
  std::string slowest;  // the stage of max_event_ms
  int unhealthy = 0;

  explicit Run(bool pf = false, bool inertial = false) {
    if (pf) cfg.engine.filter.type = engine::FilterType::kPf;
    cfg.engine.association.enabled = false;
    if (inertial) {
      cfg.engine.inertial.enabled = true;
      cfg.engine.inertial.graph.enabled = true;
      cfg.engine.inertial.mountings = {{"", "imu", {0, 0, 0}, {0, 0, 0}}, {"", "gnss", {0, 0, 0}, {0, 0, 0}}};
    }
    intake =
        std::make_unique<runtime::Intake>(stats, runtime::Intake::RejectHook{}, runtime::intake_options(cfg, false));
    for (const char* c : {"ODOMETRY", "LANDMARKS", "BEARINGS", "LOOP_CLOSURES", "IMU", "GNSS"})
      intake->add_channel(c, kind_of(c));
    engine = std::make_unique<engine::Engine>(cfg.engine);
  }
  void feed(const Record& r) {
    auto event = intake->accept(r.channel, r.bytes.data(), r.bytes.size(), runtime::Arrival::now());
    if (!event) return;
    const engine::Emit emit = [&](engine::Output o) {
      if (auto* p = std::get_if<engine::FusedPose>(&o)) {
        if (!healthy(*p)) ++unhealthy;
        poses.push_back(*p);
      }
      if (auto* g = std::get_if<engine::GeoPose>(&o)) {
        if (!healthy(*g)) ++unhealthy;
        ++geo_poses;
      }
    };
    if (!intake->resynced_body().empty())
      for (auto& s : engine->stages()) s->forget(intake->resynced_body());
    for (auto& s : engine->stages()) {
      if (!s->accepts(*event)) continue;
      const auto t0 = std::chrono::steady_clock::now();
      engine::handle_guarded(*s, *event, emit);
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      if (ms > max_event_ms) max_event_ms = ms, slowest = std::string(s->name());
    }
  }
  std::vector<engine::FusedPose> of(const std::string& source) const {
    std::vector<engine::FusedPose> out;
    for (const auto& p : poses)
      if (p.source == source) out.push_back(p);
    return out;
  }
  /// A counter of the stage named `stage` (0 when it has none of that name).
  int64_t counter(std::string_view stage, const std::string& name) const {
    for (const auto& s : engine->stages())
      if (s->name() == stage)
        for (const auto& [n, v] : s->counters())
          if (n == name) return v;
    return 0;
  }
  int64_t rejected(const std::string& channel, const std::string& reason) const {
    const auto s = stats.snapshot();
    auto it = s.at(channel).reasons.find(reason);
    return it == s.at(channel).reasons.end() ? 0 : it->second;
  }
};

/// The message of type Msg in `r`; throws when the bytes are not one.
template <class Msg>
Msg decoded(const Record& r) {
  Msg m;
  if (m.decode(r.bytes.data(), 0, static_cast<int>(r.bytes.size())) != static_cast<int>(r.bytes.size()))
    throw std::runtime_error("not a " + std::string(Msg::getTypeName()) + " on " + r.channel);
  return m;
}

/// The LCM bytes of `m`.
template <class Msg>
std::vector<uint8_t> encoded(const Msg& m) {
  std::vector<uint8_t> b(static_cast<size_t>(m.getEncodedSize()));
  if (m.encode(b.data(), 0, static_cast<int>(b.size())) != static_cast<int>(b.size()))
    throw std::runtime_error("cannot encode a " + std::string(Msg::getTypeName()));
  return b;
}

/// The poses in `a` that differ from `b`'s (count, stamps, estimators, positions), as the clean body's poses beside
/// a hostile body against those of a run without it.  The filters keep one estimate per body (equal to the last
/// bit); the graph solves every body's keyframes in one smoother, whose relinearization points another body's
/// factors move by rounding (micrometres).  -1 when the counts differ.
inline int differing_poses(const std::vector<engine::FusedPose>& a, const std::vector<engine::FusedPose>& b) {
  if (a.size() != b.size()) return -1;
  int differ = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    const double tolerance = a[i].estimator == "graph" ? 1e-3 : 1e-9;
    differ += a[i].utime != b[i].utime || a[i].estimator != b[i].estimator ||
              (a[i].pose.position - b[i].pose.position).norm() > tolerance;
  }
  return differ;
}

/// Where the value fuzzer's choices come from: a number in [0, n).
using Choose = std::function<size_t(size_t n)>;

/// Extreme but finite values, what a hostile or broken sender may put in any number: one of the usual extremes
/// (±1e308, denormals, zeros of both signs), or any finite double the choices spell out bit by bit.
inline double extreme(const Choose& choose) {
  static const double values[] = {1e308,  -1e308, 1e300, -1e300, 1e30, 1e15,    -1e15, 4.9e-324, -4.9e-324, 2.2e-308,
                                  1e-300, 0.0,    -0.0,  1.0,    -1.0, 3.14159, 1e6,   -1e6,     1e-12};
  const size_t k = choose(std::size(values) + 1);
  if (k < std::size(values)) return values[k];
  uint64_t bits = 0;
  for (int i = 0; i < 8; ++i) bits = bits << 8 | choose(256);
  double v;
  std::memcpy(&v, &bits, sizeof v);
  return std::isfinite(v) ? v : values[0];
}

/// One to three of `fields` set to extreme values.
inline void set_extreme(const std::vector<double*>& fields, const Choose& choose) {
  const size_t n = 1 + choose(3);
  for (size_t i = 0; i < n; ++i) *fields[choose(fields.size())] = extreme(choose);
}

/// A stamp moved by up to 100 s either way, sometimes.
inline void jump_in_time(int64_t& utime, const Choose& choose) {
  if (choose(8) == 0) utime += (choose(2) ? 1 : -1) * static_cast<int64_t>(choose(100'000'000));
}

inline void mutate(sextant::odometry_t& m, const Choose& choose) {
  std::vector<double*> fields;
  for (auto& v : m.position) fields.push_back(&v);
  for (auto& v : m.orientation) fields.push_back(&v);
  for (auto& v : m.covariance) fields.push_back(&v);
  for (auto& v : m.increment_covariance) fields.push_back(&v);
  for (auto& v : m.linear_velocity) fields.push_back(&v);
  for (auto& v : m.angular_velocity) fields.push_back(&v);
  for (auto& v : m.twist_covariance) fields.push_back(&v);
  set_extreme(fields, choose);
  if (choose(4) == 0) m.has_increment_covariance = !m.has_increment_covariance;
  if (choose(8) == 0) m.has_twist = !m.has_twist;
  jump_in_time(m.utime, choose);
}

inline void mutate(sextant::landmarks_t& m, const Choose& choose) {
  if (m.num_observations == 0) return;
  auto& o = m.observations[choose(static_cast<size_t>(m.num_observations))];
  std::vector<double*> fields{&o.range, &o.azimuth, &o.elevation};
  for (auto& v : o.covariance) fields.push_back(&v);
  for (auto& v : m.sensor_position) fields.push_back(&v);
  for (auto& v : m.sensor_orientation) fields.push_back(&v);
  set_extreme(fields, choose);
  if (choose(4) == 0) o.id = -1;
  if (choose(16) == 0) m.planar = !m.planar;
  jump_in_time(m.utime, choose);
}

inline void mutate(sextant::loop_closure_t& m, const Choose& choose) {
  std::vector<double*> fields;
  for (auto& v : m.position) fields.push_back(&v);
  for (auto& v : m.orientation) fields.push_back(&v);
  for (auto& v : m.information) fields.push_back(&v);
  fields.push_back(&m.score);
  set_extreme(fields, choose);
  if (choose(16) == 0) m.planar = !m.planar;
  if (choose(8) == 0) (choose(2) ? m.keyframe_from : m.keyframe_to) = static_cast<int64_t>(choose(1u << 30));
  jump_in_time(choose(2) ? m.utime_from : m.utime_to, choose);
  jump_in_time(m.utime, choose);
}

inline void mutate(sextant::imu_t& m, const Choose& choose) {
  std::vector<double*> fields;
  for (auto& v : m.angular_velocity) fields.push_back(&v);
  for (auto& v : m.angular_velocity_covariance) fields.push_back(&v);
  for (auto& v : m.linear_acceleration) fields.push_back(&v);
  for (auto& v : m.linear_acceleration_covariance) fields.push_back(&v);
  for (auto& v : m.orientation) fields.push_back(&v);
  for (auto& v : m.orientation_covariance) fields.push_back(&v);
  set_extreme(fields, choose);
  if (choose(8) == 0) m.has_orientation = !m.has_orientation;
  if (choose(8) == 0) m.orientation_has_yaw = !m.orientation_has_yaw;
  if (choose(16) == 0) (choose(2) ? m.has_angular_velocity : m.has_linear_acceleration) = false;
  jump_in_time(m.utime, choose);
}

inline void mutate(sextant::gnss_t& m, const Choose& choose) {
  std::vector<double*> fields{&m.latitude, &m.longitude, &m.altitude, &m.heading, &m.heading_variance};
  for (auto& v : m.position_covariance) fields.push_back(&v);
  for (auto& v : m.velocity) fields.push_back(&v);
  for (auto& v : m.velocity_covariance) fields.push_back(&v);
  set_extreme(fields, choose);
  if (choose(8) == 0) m.has_velocity = !m.has_velocity;
  if (choose(8) == 0) m.has_heading = !m.has_heading;
  if (choose(16) == 0) m.status = static_cast<int8_t>(static_cast<int>(choose(6)) - 1);
  jump_in_time(m.utime, choose);
}

/// `r` with its message mutated; false (and `r` unchanged) for a channel the fuzzer does not mutate (bearings go to
/// the association stage, which these runs leave off).
inline bool mutate(Record& r, const Choose& choose) {
  if (r.channel == "ODOMETRY") {
    auto m = decoded<sextant::odometry_t>(r);
    mutate(m, choose);
    r.bytes = encoded(m);
  } else if (r.channel == "LANDMARKS") {
    auto m = decoded<sextant::landmarks_t>(r);
    mutate(m, choose);
    r.bytes = encoded(m);
  } else if (r.channel == "LOOP_CLOSURES") {
    auto m = decoded<sextant::loop_closure_t>(r);
    mutate(m, choose);
    r.bytes = encoded(m);
  } else if (r.channel == "IMU") {
    auto m = decoded<sextant::imu_t>(r);
    mutate(m, choose);
    r.bytes = encoded(m);
  } else if (r.channel == "GNSS") {
    auto m = decoded<sextant::gnss_t>(r);
    mutate(m, choose);
    r.bytes = encoded(m);
  } else {
    return false;
  }
  return true;
}

/// The clean run and the victim's interleaved by time (both runs share the simulator's epoch), with the victim's
/// messages mutated where `hit()` says so, at most `max_mutated` of them; `mutated` counts them.
inline std::vector<Record> mixed(const std::vector<Record>& clean, const std::vector<Record>& victim,
                                 const std::function<bool()>& hit, const Choose& choose, int max_mutated,
                                 int& mutated) {
  std::vector<Record> out;
  size_t a = 0, b = 0;
  mutated = 0;
  while (a < clean.size() || b < victim.size()) {
    if (b >= victim.size() || (a < clean.size() && a * victim.size() <= b * clean.size())) {
      out.push_back(clean[a++]);
      continue;
    }
    Record r = victim[b++];
    if (mutated < max_mutated && hit() && mutate(r, choose)) ++mutated;
    out.push_back(std::move(r));
  }
  return out;
}

}  // namespace sextant::hostile
