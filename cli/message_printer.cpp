#include "cli/message_printer.hpp"

#include "daemon/runtime/wire_layout.hpp"

#include <sextant/bearing_scan_t.hpp>
#include <sextant/fused_pose_t.hpp>
#include <sextant/geo_pose_t.hpp>
#include <sextant/landmarks_t.hpp>
#include <sextant/loop_closure_t.hpp>
#include <sextant/match_request_t.hpp>
#include <sextant/odometry_t.hpp>
#include <sextant/status_t.hpp>
#include <sextant/targets_t.hpp>
#include <sextant/trajectory_t.hpp>
#include <sextant/truth_t.hpp>

#include <cmath>
#include <cstdio>
#include <functional>
#include <string>

namespace sextant::tools {
namespace {

std::string fmt(const char* f, auto... args) {
  char buf[512];
  std::snprintf(buf, sizeof buf, f, args...);
  return buf;
}

double yaw_deg(const double q[4]) {
  return std::atan2(2 * (q[0] * q[3] + q[1] * q[2]), 1 - 2 * (q[2] * q[2] + q[3] * q[3])) * 180.0 / M_PI;
}

std::string pose_text(const double p[3], const double q[4]) {
  return fmt("(%.3f, %.3f, %.3f) yaw %.1f deg", p[0], p[1], p[2], yaw_deg(q));
}

std::string describe(const sextant::odometry_t& m) {
  return fmt("odometry_t %s seq %lld t=%.6f source=%s ", m.sender.c_str(), (long long)m.seq, m.utime * 1e-6,
             m.source.c_str()) +
         pose_text(m.position, m.orientation);
}
std::string describe(const sextant::fused_pose_t& m) {
  return fmt("fused_pose_t %s seq %lld t=%.6f %s/%s ", m.sender.c_str(), (long long)m.seq, m.utime * 1e-6,
             m.source.c_str(), m.estimator.c_str()) +
         pose_text(m.position, m.orientation) +
         fmt(" sigma_xy %.3f m lag %.3f s", std::sqrt(std::max(0.0, m.covariance[0] + m.covariance[7])),
             m.lag_us * 1e-6);
}
std::string describe(const sextant::geo_pose_t& m) {
  return fmt("geo_pose_t %s seq %lld t=%.6f %s/%s lat %.8f lon %.8f alt %.3f sigma_en %.3f m%s", m.sender.c_str(),
             (long long)m.seq, m.utime * 1e-6, m.source.c_str(), m.estimator.c_str(), m.latitude, m.longitude,
             m.altitude, std::sqrt(std::max(0.0, m.position_covariance[0] + m.position_covariance[4])),
             m.heading_known ? "" : " (heading not yet known)");
}
std::string describe(const sextant::landmarks_t& m) {
  return fmt("landmarks_t %s seq %lld t=%.6f source=%s observations=%d", m.sender.c_str(), (long long)m.seq,
             m.utime * 1e-6, m.source.c_str(), m.num_observations);
}
std::string describe(const sextant::bearing_scan_t& m) {
  return fmt("bearing_scan_t %s seq %lld t=%.6f sensor=%d scan=%lld detections=%d", m.sender.c_str(), (long long)m.seq,
             m.utime * 1e-6, m.sensor_id, (long long)m.scan_id, m.num_detections);
}
std::string describe(const sextant::loop_closure_t& m) {
  return fmt("loop_closure_t %s seq %lld %s %.3f -> %.3f request=%lld score=%.2f", m.sender.c_str(), (long long)m.seq,
             m.source.c_str(), m.utime_from * 1e-6, m.utime_to * 1e-6, (long long)m.request_id, m.score);
}
std::string describe(const sextant::match_request_t& m) {
  return fmt("match_request_t %s seq %lld request=%lld %s keyframes %lld <-> %lld", m.sender.c_str(), (long long)m.seq,
             (long long)m.request_id, m.kind.c_str(), (long long)m.keyframe_a, (long long)m.keyframe_b);
}
std::string describe(const sextant::trajectory_t& m) {
  return fmt("trajectory_t %s seq %lld %s keyframes=%d chi2=%.4g iterations=%d solve=%.2f ms", m.sender.c_str(),
             (long long)m.seq, m.source.c_str(), m.num_keyframes, m.chi2, m.iterations, m.solve_ms);
}
std::string describe(const sextant::targets_t& m) {
  return fmt("targets_t %s seq %lld scan=%lld sensors=%d targets=%d cost=%.3f gap=%.2g%%", m.sender.c_str(),
             (long long)m.seq, (long long)m.scan_id, m.num_sensors, m.num_targets, m.total_cost, 100 * m.duality_gap);
}
std::string describe(const sextant::truth_t& m) {
  return fmt("truth_t t=%.6f %s %s id=%lld (%.3f, %.3f, %.3f)", m.utime * 1e-6, m.kind.c_str(), m.source.c_str(),
             (long long)m.id, m.position[0], m.position[1], m.position[2]);
}
std::string describe(const sextant::status_t& m) {
  std::string s = fmt("status_t %s %s uptime %.1f s", m.sender.c_str(), m.version.c_str(), m.uptime_s);
  for (const auto& c : m.channels)
    s += fmt(" | %s rx %lld ok %lld rej %lld drop %lld", c.channel.c_str(), (long long)c.received, (long long)c.decoded,
             (long long)c.rejected, (long long)c.dropped);
  for (const auto& st : m.stages)
    if (st.name != "runtime")
      s += fmt(" | %s q %d/%d p99 %.2f ms", st.name.c_str(), st.queue_depth, st.queue_capacity, st.latency_ms_p99);
  return s;
}

template <class Msg>
bool try_describe(const void* data, size_t size, std::string& out) {
  if (size < 8) return false;
  int64_t hash = 0;
  __int64_t_decode_array(data, 0, static_cast<int>(size), &hash, 1);
  if (hash != Msg::getHash()) return false;
  Msg m;
  if (runtime::safe_decode(data, size, m)) {
    out = std::string(Msg::getTypeName()) + " (truncated or corrupt)";
    return true;
  }
  out = describe(m);
  return true;
}

}  // namespace

std::string describe_message(const void* data, size_t size) {
  std::string out;
  if (try_describe<sextant::odometry_t>(data, size, out) || try_describe<sextant::fused_pose_t>(data, size, out) ||
      try_describe<sextant::geo_pose_t>(data, size, out) || try_describe<sextant::landmarks_t>(data, size, out) ||
      try_describe<sextant::bearing_scan_t>(data, size, out) ||
      try_describe<sextant::loop_closure_t>(data, size, out) ||
      try_describe<sextant::match_request_t>(data, size, out) || try_describe<sextant::trajectory_t>(data, size, out) ||
      try_describe<sextant::targets_t>(data, size, out) || try_describe<sextant::truth_t>(data, size, out) ||
      try_describe<sextant::status_t>(data, size, out))
    return out;
  return "unknown type (" + std::to_string(size) + " bytes)";
}

}  // namespace sextant::tools
