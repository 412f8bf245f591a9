// The outputs' side of the codec (codec.hpp): engine outputs into their messages, and those messages back into
// outputs for replay reports, tests and `sextant listen` (no validation beyond decoding: sextant wrote them).
#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/codec_fields.hpp"

namespace sextant::runtime {

using namespace codec_fields;

sextant::fused_pose_t to_message(const engine::FusedPose& o, const std::string& sender, int64_t seq) {
  auto m = message_header<sextant::fused_pose_t>(o.utime, sender, seq);
  m.source = o.source;
  m.estimator = o.estimator;
  m.frame = o.frame.empty() ? o.source : o.frame;
  m.planar = o.planar;
  copy_pose(o.pose, m.position, m.orientation);
  copy_row_major<6>(o.covariance, m.covariance);
  return m;
}

sextant::geo_pose_t to_message(const engine::GeoPose& o, const std::string& sender, int64_t seq) {
  auto m = message_header<sextant::geo_pose_t>(o.utime, sender, seq);
  m.source = o.source;
  m.estimator = o.estimator;
  m.heading_known = o.heading_known;
  m.latitude = o.latitude;
  m.longitude = o.longitude;
  m.altitude = o.altitude;
  copy_quaternion(o.orientation, m.orientation);
  copy_row_major<3>(o.position_covariance, m.position_covariance);
  for (int i = 0; i < 3; ++i) m.datum[i] = o.datum[i];
  return m;
}

sextant::trajectory_t to_message(const engine::Trajectory& o, const std::string& sender, int64_t seq) {
  auto m = message_header<sextant::trajectory_t>(o.utime, sender, seq);
  m.source = o.source;
  m.estimator = o.estimator;
  m.frame = o.frame.empty() ? o.source : o.frame;
  m.chi2 = o.chi2;
  m.iterations = o.iterations;
  m.solve_ms = o.solve_ms;
  m.kind =
      o.kind == engine::Trajectory::Kind::kSnapshot ? sextant::trajectory_t::SNAPSHOT : sextant::trajectory_t::UPDATE;
  m.snapshot_id = o.snapshot_id;
  m.chunk = o.chunk;
  m.num_chunks = o.num_chunks;
  m.range_first = o.range_first;
  m.range_last = o.range_last;
  m.total_keyframes = o.total_keyframes;
  m.num_removed = static_cast<int32_t>(o.removed_ids.size());
  m.removed_ids = o.removed_ids;
  m.num_keyframes = static_cast<int32_t>(o.keyframes.size());
  for (const auto& k : o.keyframes) {
    sextant::keyframe_t x{};
    x.id = k.id;
    x.utime = k.utime;
    copy_pose(k.pose, x.position, x.orientation);
    m.keyframes.push_back(x);
  }
  return m;
}

sextant::match_request_t to_message(const engine::MatchRequest& o, const std::string& sender, int64_t seq) {
  auto m = message_header<sextant::match_request_t>(o.utime, sender, seq);
  m.source = o.source;
  m.source_b = o.source_b.empty() ? o.source : o.source_b;
  m.request_id = o.request_id;
  m.kind = o.kind;
  m.keyframe_a = o.a.id;
  m.utime_a = o.a.utime;
  copy_pose(o.a.pose, m.position_a, m.orientation_a);
  m.keyframe_b = o.b.id;
  m.utime_b = o.b.utime;
  copy_pose(o.b.pose, m.position_b, m.orientation_b);
  return m;
}

sextant::targets_t to_message(const engine::Targets& o, const std::string& sender, int64_t seq) {
  auto m = message_header<sextant::targets_t>(o.utime, sender, seq);
  m.scan_id = o.scan_id;
  m.cost_kind = o.cost_kind;
  m.total_cost = o.total_cost;
  m.duality_gap = o.duality_gap;
  m.num_sensors = static_cast<int32_t>(o.sensor_ids.size());
  m.sensor_ids = o.sensor_ids;
  m.num_targets = static_cast<int32_t>(o.targets.size());
  for (const auto& t : o.targets) {
    sextant::target_t x{};
    for (int i = 0; i < 3; ++i) x.position[i] = t.position[i];
    copy_row_major<3>(t.covariance, x.covariance);
    x.num_sensors = static_cast<int32_t>(t.detection_indices.size());
    x.detection_indices = t.detection_indices;
    x.cost = t.cost;
    m.targets.push_back(x);
  }
  return m;
}

sextant::landmark_map_t to_message(const engine::LandmarkMap& o, const std::string& sender, int64_t seq) {
  auto m = message_header<sextant::landmark_map_t>(o.utime, sender, seq);
  m.frame = o.frame;
  m.num_bodies = static_cast<int32_t>(o.bodies.size());
  m.bodies = o.bodies;
  m.chunk = o.chunk;
  m.num_chunks = o.num_chunks;
  m.total_landmarks = o.total_landmarks;
  m.num_landmarks = static_cast<int32_t>(o.landmarks.size());
  for (const auto& l : o.landmarks) {
    sextant::map_landmark_t x{};
    x.id = l.id;
    for (int i = 0; i < 3; ++i) x.position[i] = l.position[i];
    x.sightings = l.sightings;
    m.landmarks.push_back(x);
  }
  return m;
}

engine::FusedPose to_output(const sextant::fused_pose_t& m) {
  engine::FusedPose o;
  o.utime = m.utime;
  o.source = m.source;
  o.estimator = m.estimator;
  o.frame = m.frame;
  o.planar = m.planar;
  o.pose = read_pose(m.position, m.orientation);
  o.covariance = read_matrix<6>(m.covariance);
  return o;
}

engine::GeoPose to_output(const sextant::geo_pose_t& m) {
  engine::GeoPose o;
  o.utime = m.utime;
  o.source = m.source;
  o.estimator = m.estimator;
  o.heading_known = m.heading_known;
  o.latitude = m.latitude;
  o.longitude = m.longitude;
  o.altitude = m.altitude;
  o.orientation = read_quaternion(m.orientation);
  o.position_covariance = read_matrix<3>(m.position_covariance);
  o.datum = Eigen::Vector3d(m.datum[0], m.datum[1], m.datum[2]);
  return o;
}

engine::Trajectory to_output(const sextant::trajectory_t& m) {
  engine::Trajectory o;
  o.utime = m.utime;
  o.source = m.source;
  o.estimator = m.estimator;
  o.frame = m.frame;
  o.chi2 = m.chi2;
  o.iterations = m.iterations;
  o.solve_ms = m.solve_ms;
  o.kind = m.kind == sextant::trajectory_t::SNAPSHOT ? engine::Trajectory::Kind::kSnapshot
                                                     : engine::Trajectory::Kind::kUpdate;
  o.snapshot_id = m.snapshot_id;
  o.chunk = m.chunk;
  o.num_chunks = m.num_chunks;
  o.range_first = m.range_first;
  o.range_last = m.range_last;
  o.total_keyframes = m.total_keyframes;
  o.removed_ids = m.removed_ids;
  for (const auto& k : m.keyframes) o.keyframes.push_back({k.id, k.utime, read_pose(k.position, k.orientation)});
  return o;
}

engine::MatchRequest to_output(const sextant::match_request_t& m) {
  engine::MatchRequest o;
  o.utime = m.utime;
  o.source = m.source;
  o.source_b = m.source_b;
  o.request_id = m.request_id;
  o.kind = m.kind;
  o.a = {m.keyframe_a, m.utime_a, read_pose(m.position_a, m.orientation_a)};
  o.b = {m.keyframe_b, m.utime_b, read_pose(m.position_b, m.orientation_b)};
  return o;
}

engine::LandmarkMap to_output(const sextant::landmark_map_t& m) {
  engine::LandmarkMap o;
  o.utime = m.utime;
  o.frame = m.frame;
  o.bodies = m.bodies;
  o.chunk = m.chunk;
  o.num_chunks = m.num_chunks;
  o.total_landmarks = m.total_landmarks;
  for (const auto& l : m.landmarks)
    o.landmarks.push_back({l.id, Eigen::Vector3d(l.position[0], l.position[1], l.position[2]), l.sightings});
  return o;
}

engine::Targets to_output(const sextant::targets_t& m) {
  engine::Targets o;
  o.utime = m.utime;
  o.scan_id = m.scan_id;
  o.cost_kind = m.cost_kind;
  o.total_cost = m.total_cost;
  o.duality_gap = m.duality_gap;
  o.sensor_ids = m.sensor_ids;
  for (const auto& t : m.targets) {
    engine::Target x;
    x.position = Eigen::Vector3d(t.position[0], t.position[1], t.position[2]);
    x.covariance = read_matrix<3>(t.covariance);
    x.detection_indices = t.detection_indices;
    x.cost = t.cost;
    o.targets.push_back(x);
  }
  return o;
}

}  // namespace sextant::runtime
