// The fleet's messages (fleet_contribution_t, fleet_control_t) <-> the engine's FleetContributions and FleetControl
// (daemon/engine/fleet_events.hpp).  Decoding validates every value as codec.cpp does for the sensors' inputs, and
// what the exchange relies on besides: names (not empty, at most 256 characters, no control characters), sequence
// numbers (>= 1, far from overflow), each kind's counts exactly as fleet_item_t.lcm lists them, flags of the kind.
#include "daemon/runtime/codec.hpp"

#include "daemon/engine/fleet_exchange.hpp"
#include "daemon/runtime/codec_fields.hpp"
#include "daemon/runtime/codec_validation.hpp"
#include "estimators/spd_matrix.hpp"

#include <cmath>
#include <sstream>

namespace sextant::runtime {

using namespace codec_fields;
using namespace codec_validation;

namespace {

constexpr int64_t kMaxSeq = int64_t{1} << 62;  // as the exchange: numbers far from overflow

SE3 check_pose(const double p[3], const double q[4], const std::string& field) {
  check_finite(p, 3, field + ".position");
  check_finite(q, 4, field + ".orientation");
  const Eigen::Quaterniond quat(q[0], q[1], q[2], q[3]);
  if (std::abs(quat.norm() - 1.0) > 1e-3) {
    std::ostringstream s;
    s << field << ".orientation: not a unit quaternion [w,x,y,z] (norm " << quat.norm() << ")";
    fail("quaternion", s.str());
  }
  return SE3(quat.normalized(), Eigen::Vector3d(p[0], p[1], p[2]));
}

// A covariance or information matrix: finite, symmetric, positive semi-definite (a planar body's unused axes are 0).
template <int N>
Eigen::Matrix<double, N, N> check_psd(const double* v, const std::string& field) {
  check_finite(v, N * N, field);
  const Eigen::Matrix<double, N, N> m = read_matrix<N>(v);
  if (!is_symmetric(m)) fail("covariance", field + ": not symmetric");
  const double smallest = smallest_eigenvalue(m), scale = std::max(1.0, m.cwiseAbs().maxCoeff());
  if (smallest < -1e-12 * scale) {
    std::ostringstream s;
    s << field << ": not positive semi-definite (smallest eigenvalue " << smallest << ")";
    fail("covariance", s.str());
  }
  return m;
}

slam::KeyframeAnchor check_anchor(const sextant::fleet_anchor_t& a, const std::string& field) {
  if (a.keyframe < 0) fail("invalid", field + ".keyframe: negative");
  slam::KeyframeAnchor out;
  out.keyframe = a.keyframe;
  out.motion = check_pose(a.position, a.orientation, field);
  out.covariance = check_psd<6>(a.covariance, field + ".covariance");
  return out;
}

slam::LandmarkSighting check_sighting(const sextant::landmark_observation_t& o, const std::string& field) {
  slam::LandmarkSighting s;
  if (o.id < 0) fail("invalid", field + ".id: negative (only identified landmarks and markers are contributed)");
  s.id = o.id;
  check_finite(&o.range, 1, field + ".range");
  check_finite(&o.azimuth, 1, field + ".azimuth");
  check_finite(&o.elevation, 1, field + ".elevation");
  if (!(o.range > 0)) fail("invalid", field + ".range: not positive");
  s.range = o.range, s.azimuth = o.azimuth, s.elevation = o.elevation;
  s.covariance = check_psd<3>(o.covariance, field + ".covariance");
  if (!(s.covariance(0, 0) > 0 && s.covariance(1, 1) > 0))
    fail("covariance", field + ".covariance: range or azimuth variance not positive");
  return s;
}

// The counts each kind carries (fleet_item_t.lcm).
struct Counts {
  int poses, anchors, min_sightings, max_sightings;
  int flags;  // the flags the kind may have
  int min_keyframes = 0, max_keyframes = 0;
};

Counts counts_of(const sextant::fleet_item_t& it, const std::string& field) {
  using I = sextant::fleet_item_t;
  switch (it.kind) {
    case I::KEYFRAME:
      return {(it.flags & I::FIRST) != 0 ? 1 : 2, 0, 0, 0, I::FIRST | I::REANCHORED};
    case I::SIGHTINGS:
      return {1, 1, 1, static_cast<int>(engine::fleet::kMaxSightingsPerItem), 0};
    case I::BODY_SIGHTING_HALF:
      return {1, 1, 1, 1, 0};
    case I::BODY_SIGHTING:
      return {1, 2, 1, 1, 0};
    case I::LOOP:
      return {1, 0, 0, 0, I::WIDENED};
    case I::BODY_LOOP_HALF:
    case I::BODY_LOOP:
      return {1, it.kind == I::BODY_LOOP_HALF ? 1 : 0, 0, 0, 0};
    case I::FRAME_JOIN:
      return {1, 0, 0, 0, 0};
    case I::THINNED:
      return {0, 0, 0, 0, 0, 1, static_cast<int>(engine::fleet::kMaxThinnedPerItem)};
    default:
      fail("invalid", field + ".kind: unknown (" + std::to_string(it.kind) + ")");
  }
}

void check_counts(const sextant::fleet_item_t& it, const std::string& field) {
  const Counts c = counts_of(it, field);
  if ((it.flags & ~c.flags) != 0) fail("invalid", field + ".flags: " + std::to_string(it.flags) + " not of its kind");
  if (it.num_poses != c.poses || static_cast<int>(it.poses.size()) != c.poses)
    fail("invalid",
         field + ".num_poses: " + std::to_string(it.num_poses) + ", its kind has " + std::to_string(c.poses));
  if (it.num_anchors != c.anchors || static_cast<int>(it.anchors.size()) != c.anchors)
    fail("invalid",
         field + ".num_anchors: " + std::to_string(it.num_anchors) + ", its kind has " + std::to_string(c.anchors));
  if (it.num_sightings < c.min_sightings || it.num_sightings > c.max_sightings ||
      static_cast<int>(it.sightings.size()) != it.num_sightings)
    fail("invalid", field + ".num_sightings: " + std::to_string(it.num_sightings) + " outside [" +
                        std::to_string(c.min_sightings) + ", " + std::to_string(c.max_sightings) + "]");
  if (it.num_keyframes < c.min_keyframes || it.num_keyframes > c.max_keyframes ||
      static_cast<int>(it.keyframes.size()) != it.num_keyframes)
    fail("invalid", field + ".num_keyframes: " + std::to_string(it.num_keyframes) + " outside [" +
                        std::to_string(c.min_keyframes) + ", " + std::to_string(c.max_keyframes) + "]");
  for (size_t i = 0; i < it.keyframes.size(); ++i)
    if (it.keyframes[i] < 0) fail("invalid", field + ".keyframes[" + std::to_string(i) + "]: negative keyframe id");
  const bool other = it.kind == sextant::fleet_item_t::BODY_SIGHTING_HALF ||
                     it.kind == sextant::fleet_item_t::BODY_SIGHTING || it.kind == sextant::fleet_item_t::BODY_LOOP ||
                     it.kind == sextant::fleet_item_t::BODY_LOOP_HALF || it.kind == sextant::fleet_item_t::FRAME_JOIN;
  check_name(it.other, field + ".other", !other);
  if (!other && !it.other.empty()) fail("invalid", field + ".other: set on a kind without another body");
}

// The pieces of a checked item.
struct Parts {
  std::vector<SE3> poses;
  std::vector<Matrix6d> matrices;
  std::vector<slam::KeyframeAnchor> anchors;
  std::vector<slam::LandmarkSighting> sightings;
};

Parts check_parts(const sextant::fleet_item_t& it, const std::string& field) {
  Parts p;
  for (size_t i = 0; i < it.poses.size(); ++i) {
    const std::string f = field + ".poses[" + std::to_string(i) + "]";
    p.poses.push_back(check_pose(it.poses[i].position, it.poses[i].orientation, f));
    p.matrices.push_back(check_psd<6>(it.poses[i].matrix, f + ".matrix"));
  }
  for (size_t i = 0; i < it.anchors.size(); ++i)
    p.anchors.push_back(check_anchor(it.anchors[i], field + ".anchors[" + std::to_string(i) + "]"));
  for (size_t i = 0; i < it.sightings.size(); ++i)
    p.sightings.push_back(check_sighting(it.sightings[i], field + ".sightings[" + std::to_string(i) + "]"));
  return p;
}

slam::KeyframeContribution keyframe_of(const sextant::fleet_item_t& it, Parts& p) {
  slam::KeyframeContribution k;
  k.id = it.keyframe_a;
  k.utime = it.utime;
  k.planar = it.planar;
  k.first = (it.flags & sextant::fleet_item_t::FIRST) != 0;
  k.reanchored = (it.flags & sextant::fleet_item_t::REANCHORED) != 0;
  k.odom = p.poses[0];
  k.odom_covariance = p.matrices[0];
  if (!k.first) {
    k.edge = p.poses[1];
    k.edge_covariance = p.matrices[1];
  }
  return k;
}

engine::fleet::What sightings_of(const sextant::fleet_item_t& it, Parts& p) {
  using I = sextant::fleet_item_t;
  if (it.kind == I::SIGHTINGS) {
    slam::SightingsContribution s;
    s.anchor = p.anchors[0];
    s.sightings.utime = it.utime;
    s.sightings.planar = it.planar;
    s.sightings.sensor_in_body = p.poses[0];
    s.sightings.sightings = std::move(p.sightings);
    return s;
  }
  if (it.kind == I::BODY_SIGHTING_HALF)
    return slam::BodySightingHalf{it.other, it.utime, p.poses[0], p.sightings[0], p.anchors[0]};
  return slam::BodySighting{it.other, it.utime, p.poses[0], p.sightings[0], p.anchors[0], p.anchors[1]};
}

engine::fleet::What loop_of(const sextant::fleet_item_t& it, Parts& p) {
  using I = sextant::fleet_item_t;
  if (it.kind == I::LOOP)
    return slam::LoopContribution{it.keyframe_a, it.keyframe_b, p.poses[0], p.matrices[0],
                                  (it.flags & I::WIDENED) != 0};
  if (it.kind == I::BODY_LOOP) return slam::BodyLoop{it.other, it.keyframe_a, it.keyframe_b, p.poses[0], p.matrices[0]};
  slam::BodyLoopHalf h;
  h.loop.utime_from = it.utime;
  h.loop.utime_to = it.utime_to;
  h.loop.keyframe_from = it.keyframe_a;
  h.loop.keyframe_to = it.keyframe_b;
  h.loop.relative = p.poses[0];
  h.loop.information = p.matrices[0];
  h.loop.body_to = it.other;
  h.from = p.anchors[0];
  return h;
}

engine::fleet::What item_of(const sextant::fleet_item_t& it, const std::string& field) {
  using I = sextant::fleet_item_t;
  check_counts(it, field);
  const bool timed = it.kind != I::LOOP && it.kind != I::BODY_LOOP && it.kind != I::FRAME_JOIN && it.kind != I::THINNED;
  if (timed && it.utime <= 0) fail("invalid", field + ".utime: not positive (" + std::to_string(it.utime) + ")");
  if (it.kind == I::BODY_LOOP_HALF && it.utime_to <= 0) fail("invalid", field + ".utime_to: not positive");
  if (it.kind == I::KEYFRAME && it.keyframe_a < 0) fail("invalid", field + ".keyframe_a: negative keyframe id");
  if ((it.kind == I::LOOP || it.kind == I::BODY_LOOP) && (it.keyframe_a < 0 || it.keyframe_b < 0))
    fail("invalid", field + ".keyframe_a/keyframe_b: negative keyframe id");
  if (it.kind == I::BODY_LOOP_HALF && (it.keyframe_a < -1 || it.keyframe_b < -1))
    fail("invalid", field + ".keyframe_a/keyframe_b: below -1 (unknown)");
  Parts p = check_parts(it, field);
  if (it.kind == I::KEYFRAME) return keyframe_of(it, p);
  if (it.kind == I::FRAME_JOIN) return slam::FrameJoin{it.other, p.poses[0]};
  if (it.kind == I::THINNED) return slam::KeyframesThinned{it.keyframes};
  if (it.kind == I::SIGHTINGS || it.kind == I::BODY_SIGHTING_HALF || it.kind == I::BODY_SIGHTING)
    return sightings_of(it, p);
  return loop_of(it, p);
}

}  // namespace

std::string fleet_item_error(const engine::fleet::What& what) {
  const Decoded d = guarded([&]() -> Decoded {
    item_of(to_item(what), "fleet_item_t");
    return engine::Event{};
  });
  const auto* r = std::get_if<Rejection>(&d);
  return r == nullptr ? std::string() : r->reason + ": " + r->message;
}

Decoded to_event(const sextant::fleet_contribution_t& m) {
  return guarded([&]() -> Decoded {
    check_name(m.sender, "fleet_contribution_t.sender", false);
    check_name(m.body, "fleet_contribution_t.body", false);
    const auto n = static_cast<int64_t>(m.num_contributions);
    if (n < 1 || n > static_cast<int64_t>(engine::fleet::kMaxItemsPerMessage) ||
        static_cast<int64_t>(m.contributions.size()) != n)
      fail("too_large", "fleet_contribution_t.num_contributions: " + std::to_string(n) + " outside [1, 1024]");
    if (m.first < 1 || m.first > kMaxSeq - n)
      fail("invalid", "fleet_contribution_t.first: " + std::to_string(m.first) + " outside [1, 2^62]");
    engine::FleetContributions e;
    e.utime = m.utime;
    e.sender = m.sender;
    e.body = m.body;
    e.repair = m.repair;
    e.first = m.first;
    e.contributions.reserve(static_cast<size_t>(n));
    for (size_t i = 0; i < m.contributions.size(); ++i)
      e.contributions.push_back(
          item_of(m.contributions[i], "fleet_contribution_t.contributions[" + std::to_string(i) + "]"));
    return engine::Event{std::move(e)};
  });
}

Decoded to_event(const sextant::fleet_control_t& m) {
  return guarded([&]() -> Decoded {
    using C = sextant::fleet_control_t;
    check_name(m.sender, "fleet_control_t.sender", false);
    if (m.kind != C::HEARTBEAT && m.kind != C::REPAIR)
      fail("invalid", "fleet_control_t.kind: unknown (" + std::to_string(m.kind) + ")");
    check_name(m.daemon, "fleet_control_t.daemon", m.kind == C::HEARTBEAT);
    if (m.kind == C::HEARTBEAT && !m.daemon.empty()) fail("invalid", "fleet_control_t.daemon: set on a heartbeat");
    if (m.num_streams < 0 || m.num_streams > static_cast<int>(engine::fleet::kMaxRangesPerMessage) ||
        static_cast<int>(m.streams.size()) != m.num_streams)
      fail("too_large", "fleet_control_t.num_streams: " + std::to_string(m.num_streams) + " outside [0, 1024]");
    engine::FleetControl e;
    e.utime = m.utime;
    e.sender = m.sender;
    e.kind = m.kind == C::HEARTBEAT ? engine::FleetControl::Kind::kHeartbeat : engine::FleetControl::Kind::kRepair;
    e.daemon = m.daemon;
    for (size_t i = 0; i < m.streams.size(); ++i) {
      const auto& r = m.streams[i];
      const std::string f = "fleet_control_t.streams[" + std::to_string(i) + "]";
      check_name(r.body, f + ".body", false);
      const int64_t lo = m.kind == C::HEARTBEAT ? 0 : 1;
      if (r.first < lo || r.last < r.first || r.last > kMaxSeq)
        fail("invalid",
             f + ": range [" + std::to_string(r.first) + ", " + std::to_string(r.last) + "] not of its kind");
      e.streams.push_back(engine::FleetRange{r.body, r.first, r.last});
    }
    return engine::Event{std::move(e)};
  });
}

namespace {

sextant::fleet_pose_t pose_message(const SE3& x, const Matrix6d& m) {
  sextant::fleet_pose_t p{};
  copy_pose(engine::Pose{x.translation(), x.rotation().quaternion()}, p.position, p.orientation);
  copy_row_major<6>(m, p.matrix);
  return p;
}

sextant::fleet_anchor_t anchor_message(const slam::KeyframeAnchor& a) {
  sextant::fleet_anchor_t out{};
  out.keyframe = a.keyframe;
  copy_pose(engine::Pose{a.motion.translation(), a.motion.rotation().quaternion()}, out.position, out.orientation);
  copy_row_major<6>(a.covariance, out.covariance);
  return out;
}

sextant::landmark_observation_t sighting_message(const slam::LandmarkSighting& s) {
  sextant::landmark_observation_t o{};
  o.id = s.id;
  o.range = s.range, o.azimuth = s.azimuth, o.elevation = s.elevation;
  copy_row_major<3>(s.covariance, o.covariance);
  return o;
}

void fill_item(sextant::fleet_item_t& it, const slam::KeyframeContribution& k) {
  using I = sextant::fleet_item_t;
  it.kind = I::KEYFRAME;
  it.flags = static_cast<int8_t>((k.first ? I::FIRST : 0) | (k.reanchored ? I::REANCHORED : 0));
  it.utime = k.utime, it.planar = k.planar, it.keyframe_a = k.id;
  it.poses.push_back(pose_message(k.odom, k.odom_covariance));
  if (!k.first) it.poses.push_back(pose_message(k.edge, k.edge_covariance));
}

void fill_item(sextant::fleet_item_t& it, const slam::SightingsContribution& s) {
  it.kind = sextant::fleet_item_t::SIGHTINGS;
  it.utime = s.sightings.utime, it.planar = s.sightings.planar;
  it.poses.push_back(pose_message(s.sightings.sensor_in_body, Matrix6d::Zero()));
  it.anchors.push_back(anchor_message(s.anchor));
  for (const auto& x : s.sightings.sightings) it.sightings.push_back(sighting_message(x));
}

void fill_item(sextant::fleet_item_t& it, const slam::BodySightingHalf& s) {
  it.kind = sextant::fleet_item_t::BODY_SIGHTING_HALF;
  it.utime = s.utime, it.other = s.observed;
  it.poses.push_back(pose_message(s.sensor_in_body, Matrix6d::Zero()));
  it.anchors.push_back(anchor_message(s.observer));
  it.sightings.push_back(sighting_message(s.sighting));
}

void fill_item(sextant::fleet_item_t& it, const slam::BodySighting& s) {
  it.kind = sextant::fleet_item_t::BODY_SIGHTING;
  it.utime = s.utime, it.other = s.observer;
  it.poses.push_back(pose_message(s.sensor_in_body, Matrix6d::Zero()));
  it.anchors.push_back(anchor_message(s.observer_anchor));
  it.anchors.push_back(anchor_message(s.observed_anchor));
  it.sightings.push_back(sighting_message(s.sighting));
}

void fill_item(sextant::fleet_item_t& it, const slam::LoopContribution& l) {
  it.kind = sextant::fleet_item_t::LOOP;
  it.flags = l.widened ? sextant::fleet_item_t::WIDENED : 0;
  it.keyframe_a = l.from_keyframe, it.keyframe_b = l.to_keyframe;
  it.poses.push_back(pose_message(l.z, l.information));
}

void fill_item(sextant::fleet_item_t& it, const slam::BodyLoopHalf& h) {
  it.kind = sextant::fleet_item_t::BODY_LOOP_HALF;
  it.utime = h.loop.utime_from, it.utime_to = h.loop.utime_to, it.other = h.loop.body_to;
  it.keyframe_a = h.loop.keyframe_from, it.keyframe_b = h.loop.keyframe_to;
  it.poses.push_back(pose_message(h.loop.relative, h.loop.information));
  it.anchors.push_back(anchor_message(h.from));
}

void fill_item(sextant::fleet_item_t& it, const slam::FrameJoin& j) {
  it.kind = sextant::fleet_item_t::FRAME_JOIN;
  it.other = j.keep;
  it.poses.push_back(pose_message(j.keep_from_gone, Matrix6d::Zero()));
}

void fill_item(sextant::fleet_item_t& it, const slam::KeyframesThinned& t) {
  it.kind = sextant::fleet_item_t::THINNED;
  it.keyframes = t.keyframes;
}

void fill_item(sextant::fleet_item_t& it, const slam::BodyLoop& l) {
  it.kind = sextant::fleet_item_t::BODY_LOOP;
  it.other = l.from, it.keyframe_a = l.from_keyframe, it.keyframe_b = l.to_keyframe;
  it.poses.push_back(pose_message(l.z, l.information));
}

}  // namespace

sextant::fleet_item_t to_item(const engine::fleet::What& what) {
  sextant::fleet_item_t it{};
  std::visit([&](const auto& x) { fill_item(it, x); }, what);
  it.num_poses = static_cast<int32_t>(it.poses.size());
  it.num_anchors = static_cast<int32_t>(it.anchors.size());
  it.num_sightings = static_cast<int32_t>(it.sightings.size());
  it.num_keyframes = static_cast<int32_t>(it.keyframes.size());
  return it;
}

sextant::fleet_contribution_t to_message(const engine::FleetContributions& o, const std::string& sender, int64_t seq) {
  auto m = message_header<sextant::fleet_contribution_t>(o.utime, sender, seq);
  m.body = o.body;
  m.repair = o.repair;
  m.first = o.first;
  m.num_contributions = static_cast<int32_t>(o.contributions.size());
  for (const auto& w : o.contributions) m.contributions.push_back(to_item(w));
  return m;
}

sextant::fleet_control_t to_message(const engine::FleetControl& o, const std::string& sender, int64_t seq) {
  auto m = message_header<sextant::fleet_control_t>(o.utime, sender, seq);
  m.kind = o.kind == engine::FleetControl::Kind::kHeartbeat ? sextant::fleet_control_t::HEARTBEAT
                                                            : sextant::fleet_control_t::REPAIR;
  m.daemon = o.daemon;
  m.num_streams = static_cast<int32_t>(o.streams.size());
  for (const auto& r : o.streams) {
    sextant::fleet_range_t x{};
    x.body = r.body, x.first = r.first, x.last = r.last;
    m.streams.push_back(x);
  }
  return m;
}

}  // namespace sextant::runtime
