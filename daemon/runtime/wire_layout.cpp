#include "daemon/runtime/wire_layout.hpp"

#include "daemon/runtime/codec.hpp"

namespace sextant::runtime {
namespace {

using Kind = WireField::Kind;

WireField fixed(std::string name, size_t bytes) { return {std::move(name), Kind::kFixed, bytes, 0, nullptr}; }
WireField i64(std::string name) { return fixed(std::move(name), 8); }
WireField i32(std::string name) { return fixed(std::move(name), 4); }
WireField boolean(std::string name) { return fixed(std::move(name), 1); }
WireField i8(std::string name) { return fixed(std::move(name), 1); }
WireField doubles(std::string name, size_t n) { return fixed(std::move(name), 8 * n); }
WireField str(std::string name) { return {std::move(name), Kind::kString, 0, 0, nullptr}; }
WireField count(std::string name, int32_t max) { return {std::move(name), Kind::kCount, 4, max, nullptr}; }
WireField array(std::string name, const WireLayout& element) { return {std::move(name), Kind::kArray, 0, 0, &element}; }

// Elements of primitive arrays (`string names[n]`, `int64_t values[n]`): one unnamed field.
const WireLayout kStringElement{"string", {str("")}};
const WireLayout kInt64Element{"int64_t", {i64("")}};
const WireLayout kInt32Element{"int32_t", {i32("")}};
const WireLayout kDoubleElement{"double", {doubles("", 1)}};
// The outputs' counts are bounded by the bytes (an element takes at least min_size() of them) more than by these
// maxima, which only keep a claimed count within what any sender of these messages produces.
constexpr int32_t kMaxListed = 1 << 16;  // channels, stages, counters, outputs, sensors
constexpr int32_t kMaxItems = 1 << 22;   // keyframes, removed ids, targets

int32_t read_i32(const uint8_t* p) {
  return static_cast<int32_t>((uint32_t{p[0]} << 24) | (uint32_t{p[1]} << 16) | (uint32_t{p[2]} << 8) | uint32_t{p[3]});
}

class Walker {
 public:
  Walker(const uint8_t* data, size_t size) : data_(data), size_(size) {}

  // Field names in errors are relative to `layout`; callers prepend their own (no string is built unless one fails).
  std::optional<WireError> walk(const WireLayout& layout) {
    int64_t pending_count = -1;
    for (const auto& f : layout.fields) {
      const std::string& name = f.name;
      switch (f.kind) {
        case Kind::kFixed:
          if (f.bytes > left()) return truncated(name, f.bytes);
          pos_ += f.bytes;
          break;
        case Kind::kString: {
          if (4 > left()) return truncated(name, 4);
          const int32_t n = read_i32(data_ + pos_);
          const size_t at = pos_;
          pos_ += 4;
          if (n < 1)
            return WireError{"decode", name + ": string length " + std::to_string(n) + " at byte " +
                                           std::to_string(at) + " (the length counts the terminating NUL: at least 1)"};
          if (static_cast<size_t>(n) > left())
            return WireError{"decode", name + ": string length " + std::to_string(n) + " at byte " +
                                           std::to_string(at) + " exceeds the " + std::to_string(left()) +
                                           " bytes left"};
          if (data_[pos_ + static_cast<size_t>(n) - 1] != 0)
            return WireError{"decode", name + ": string at byte " + std::to_string(at) + " does not end in NUL"};
          pos_ += static_cast<size_t>(n);
          break;
        }
        case Kind::kCount: {
          if (4 > left()) return truncated(name, 4);
          const int32_t n = read_i32(data_ + pos_);
          if (n < 0 || n > f.max_count)
            return WireError{n < 0 ? "decode" : "too_large", name + ": " + std::to_string(n) + " at byte " +
                                                                 std::to_string(pos_) + " outside [0, " +
                                                                 std::to_string(f.max_count) + "]"};
          pending_count = n;
          pos_ += 4;
          break;
        }
        case Kind::kArray: {
          const size_t n = pending_count < 0 ? 0 : static_cast<size_t>(pending_count);
          const size_t min = f.element->min_size();
          if (min > 0 && n > left() / min)
            return WireError{"decode", name + ": " + std::to_string(n) + " elements of at least " +
                                           std::to_string(min) + " bytes exceed the " + std::to_string(left()) +
                                           " bytes left"};
          for (size_t i = 0; i < n; ++i)
            if (auto e = walk(*f.element)) {
              // An element that is a struct names its field ("[2].name: ..."), a primitive element does not ("[2]: ...").
              e->message = name + "[" + std::to_string(i) + "]" + (e->message[0] == ':' ? "" : ".") + e->message;
              return e;
            }
          break;  // the count stays: several arrays can share one (status_t's outputs)
        }
      }
    }
    return std::nullopt;
  }

  size_t pos_ = 8;  // after the fingerprint

 private:
  size_t left() const { return size_ - pos_; }
  WireError truncated(const std::string& name, size_t need) const {
    return WireError{"decode", name + ": truncated at byte " + std::to_string(pos_) + " (" + std::to_string(need) +
                                   " bytes needed, " + std::to_string(left()) + " left)"};
  }

  const uint8_t* data_;
  size_t size_;
};

}  // namespace

size_t WireLayout::min_size() const {
  size_t n = 0;
  for (const auto& f : fields) {
    if (f.kind == Kind::kFixed || f.kind == Kind::kCount)
      n += f.bytes;
    else if (f.kind == Kind::kString)
      n += 5;
  }
  return n;
}

std::optional<WireError> wire_error(const WireLayout& layout, const void* data, size_t size) {
  if (size < 8) return WireError{"decode", layout.type + ": shorter than an LCM fingerprint"};
  Walker w(static_cast<const uint8_t*>(data), size);
  auto e = w.walk(layout);
  if (e) e->message = layout.type + "." + e->message;
  return e;
}

template <>
const WireLayout& wire_layout<sextant::odometry_t>() {
  static const WireLayout l{
      "odometry_t",
      {i64("utime"), str("sender"), i64("seq"), str("source"), boolean("planar"), doubles("position", 3),
       doubles("orientation", 4), doubles("covariance", 36), boolean("has_increment_covariance"),
       doubles("increment_covariance", 36), boolean("has_twist"), doubles("linear_velocity", 3),
       doubles("angular_velocity", 3), doubles("twist_covariance", 36)}};
  return l;
}

template <>
const WireLayout& wire_layout<sextant::landmarks_t>() {
  static const WireLayout observation{
      "landmark_observation_t",
      {i64("id"), doubles("range", 1), doubles("azimuth", 1), doubles("elevation", 1), doubles("covariance", 9)}};
  static const WireLayout l{
      "landmarks_t",
      {i64("utime"), str("sender"), i64("seq"), str("source"), boolean("planar"), doubles("sensor_position", 3),
       doubles("sensor_orientation", 4), count("num_observations", kMaxObservationsPerMessage),
       array("observations", observation)}};
  return l;
}

template <>
const WireLayout& wire_layout<sextant::bearing_scan_t>() {
  static const WireLayout detection{
      "bearing_detection_t",
      {doubles("azimuth", 1), doubles("elevation", 1), doubles("sigma_azimuth", 1), doubles("sigma_elevation", 1)}};
  static const WireLayout l{
      "bearing_scan_t",
      {i64("utime"), str("sender"), i64("seq"), i32("sensor_id"), doubles("sensor_position", 3), i64("scan_id"),
       count("num_detections", kMaxDetectionsPerScan), array("detections", detection)}};
  return l;
}

template <>
const WireLayout& wire_layout<sextant::imu_t>() {
  static const WireLayout l{
      "imu_t",
      {i64("utime"), str("sender"), i64("seq"), str("source"), str("frame"), boolean("has_angular_velocity"),
       doubles("angular_velocity", 3), doubles("angular_velocity_covariance", 9), boolean("has_linear_acceleration"),
       doubles("linear_acceleration", 3), doubles("linear_acceleration_covariance", 9), boolean("has_orientation"),
       boolean("orientation_has_yaw"), doubles("orientation", 4), doubles("orientation_covariance", 9)}};
  return l;
}

template <>
const WireLayout& wire_layout<sextant::gnss_t>() {
  static const WireLayout l{
      "gnss_t",
      {i64("utime"), str("sender"), i64("seq"), str("source"), str("frame"), i8("status"), doubles("latitude", 1),
       doubles("longitude", 1), doubles("altitude", 1), i8("covariance_type"), doubles("position_covariance", 9),
       boolean("has_velocity"), doubles("velocity", 3), doubles("velocity_covariance", 9), boolean("has_heading"),
       doubles("heading", 1), doubles("heading_variance", 1)}};
  return l;
}

template <>
const WireLayout& wire_layout<sextant::loop_closure_t>() {
  static const WireLayout l{
      "loop_closure_t",
      {i64("utime"), str("sender"), i64("seq"), str("source"), str("source_to"), boolean("planar"), i64("utime_from"),
       i64("utime_to"), i64("keyframe_from"), i64("keyframe_to"), i64("request_id"), doubles("position", 3),
       doubles("orientation", 4), doubles("information", 36), str("matcher"), doubles("score", 1)}};
  return l;
}

template <>
const WireLayout& wire_layout<sextant::truth_t>() {
  static const WireLayout l{"truth_t",
                            {i64("utime"), str("sender"), i64("seq"), str("kind"), str("source"), i64("id"),
                             doubles("position", 3), doubles("orientation", 4)}};
  return l;
}

template <>
const WireLayout& wire_layout<sextant::match_request_t>() {
  static const WireLayout l{
      "match_request_t",
      {i64("utime"), str("sender"), i64("seq"), str("source"), str("source_b"), i64("request_id"), str("kind"),
       i64("keyframe_a"), i64("utime_a"), doubles("position_a", 3), doubles("orientation_a", 4), i64("keyframe_b"),
       i64("utime_b"), doubles("position_b", 3), doubles("orientation_b", 4)}};
  return l;
}

template <>
const WireLayout& wire_layout<sextant::fused_pose_t>() {
  static const WireLayout l{
      "fused_pose_t",
      {i64("utime"), str("sender"), i64("seq"), str("source"), str("estimator"), str("frame"), boolean("planar"),
       doubles("position", 3), doubles("orientation", 4), doubles("covariance", 36), i64("lag_us")}};
  return l;
}

template <>
const WireLayout& wire_layout<sextant::geo_pose_t>() {
  static const WireLayout l{
      "geo_pose_t",
      {i64("utime"), str("sender"), i64("seq"), str("source"), str("estimator"), boolean("heading_known"),
       doubles("latitude", 1), doubles("longitude", 1), doubles("altitude", 1), doubles("orientation", 4),
       doubles("position_covariance", 9), doubles("datum", 3)}};
  return l;
}

template <>
const WireLayout& wire_layout<sextant::status_t>() {
  static const WireLayout channel{
      "channel_status_t",
      {str("channel"), i64("received"), i64("decoded"), i64("rejected"), i64("dropped"), i64("lost"),
       count("num_reasons", kMaxListed), array("reasons", kStringElement), array("reason_counts", kInt64Element),
       str("last_error"), count("num_lost_senders", kMaxListed), array("lost_senders", kStringElement),
       array("lost_counts", kInt64Element)}};
  static const WireLayout stage{
      "stage_status_t",
      {str("name"), i32("queue_depth"), i32("queue_capacity"), i64("processed"), i64("dropped"),
       doubles("latency_ms_p50", 1), doubles("latency_ms_p90", 1), doubles("latency_ms_p99", 1),
       doubles("latency_ms_max", 1), count("num_counters", kMaxListed), array("counter_names", kStringElement),
       array("counter_values", kInt64Element), str("last_failure")}};
  static const WireLayout l{"status_t",
                            {i64("utime"), str("sender"), i64("seq"), str("version"), doubles("uptime_s", 1),
                             count("num_channels", kMaxListed), array("channels", channel),
                             count("num_stages", kMaxListed), array("stages", stage), count("num_outputs", kMaxListed),
                             array("output_channels", kStringElement), array("output_counts", kInt64Element),
                             array("output_bytes", kInt64Element), array("output_bytes_per_s", kDoubleElement)}};
  return l;
}

template <>
const WireLayout& wire_layout<sextant::trajectory_t>() {
  static const WireLayout keyframe{"keyframe_t",
                                   {i64("id"), i64("utime"), doubles("position", 3), doubles("orientation", 4)}};
  static const WireLayout l{"trajectory_t",
                            {i64("utime"),
                             str("sender"),
                             i64("seq"),
                             str("source"),
                             str("estimator"),
                             str("frame"),
                             doubles("chi2", 1),
                             i32("iterations"),
                             doubles("solve_ms", 1),
                             fixed("kind", 1),
                             i64("snapshot_id"),
                             i32("chunk"),
                             i32("num_chunks"),
                             i64("range_first"),
                             i64("range_last"),
                             i32("total_keyframes"),
                             count("num_keyframes", kMaxItems),
                             array("keyframes", keyframe),
                             count("num_removed", kMaxItems),
                             array("removed_ids", kInt64Element)}};
  return l;
}

template <>
const WireLayout& wire_layout<sextant::landmark_map_t>() {
  static const WireLayout landmark{"map_landmark_t", {i64("id"), doubles("position", 3), i32("sightings")}};
  static const WireLayout l{"landmark_map_t",
                            {i64("utime"), str("sender"), i64("seq"), str("frame"), count("num_bodies", kMaxListed),
                             array("bodies", kStringElement), i32("chunk"), i32("num_chunks"), i32("total_landmarks"),
                             count("num_landmarks", kMaxItems), array("landmarks", landmark)}};
  return l;
}

template <>
const WireLayout& wire_layout<sextant::targets_t>() {
  static const WireLayout target{"target_t",
                                 {doubles("position", 3), doubles("covariance", 9), count("num_sensors", kMaxListed),
                                  array("detection_indices", kInt32Element), doubles("cost", 1)}};
  static const WireLayout l{
      "targets_t",
      {i64("utime"), str("sender"), i64("seq"), i64("scan_id"), str("cost_kind"), doubles("total_cost", 1),
       doubles("duality_gap", 1), count("num_sensors", kMaxListed), array("sensor_ids", kInt32Element),
       count("num_targets", kMaxItems), array("targets", target)}};
  return l;
}

// The fleet's messages (lcmtypes/sextant/fleet_*.lcm).  The counts' maxima are the codec's own bounds, so that a count
// beyond them is refused before anything is allocated.
template <>
const WireLayout& wire_layout<sextant::fleet_contribution_t>() {
  static const WireLayout pose{"fleet_pose_t",
                               {doubles("position", 3), doubles("orientation", 4), doubles("matrix", 36)}};
  static const WireLayout anchor{
      "fleet_anchor_t",
      {i64("keyframe"), doubles("position", 3), doubles("orientation", 4), doubles("covariance", 36)}};
  static const WireLayout observation{
      "landmark_observation_t",
      {i64("id"), doubles("range", 1), doubles("azimuth", 1), doubles("elevation", 1), doubles("covariance", 9)}};
  static const WireLayout item{
      "fleet_item_t",
      {i8("kind"), i8("flags"), i64("utime"), i64("utime_to"), boolean("planar"), str("other"), i64("keyframe_a"),
       i64("keyframe_b"), count("num_poses", 2), array("poses", pose), count("num_anchors", 2),
       array("anchors", anchor), count("num_sightings", 256), array("sightings", observation),
       count("num_keyframes", 1024), array("keyframes", kInt64Element)}};
  static const WireLayout l{"fleet_contribution_t",
                            {i64("utime"), str("sender"), i64("seq"), str("body"), boolean("repair"), i64("first"),
                             count("num_contributions", 1024), array("contributions", item)}};
  return l;
}

template <>
const WireLayout& wire_layout<sextant::fleet_control_t>() {
  static const WireLayout range{"fleet_range_t", {str("body"), i64("first"), i64("last")}};
  static const WireLayout l{"fleet_control_t",
                            {i64("utime"), str("sender"), i64("seq"), i8("kind"), str("daemon"),
                             count("num_streams", 1024), array("streams", range)}};
  return l;
}

}  // namespace sextant::runtime
