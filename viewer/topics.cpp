#include "viewer/topics.hpp"

#include "daemon/engine/trajectory_rebuild.hpp"
#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/wire_layout.hpp"
#include "viewer/foxglove_schemas.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <optional>
#include <set>
#include <stdexcept>

namespace sextant::viewer {
namespace {

// ---- Foxglove JSON building blocks ----
Json stamp(int64_t utime) {
  const int64_t us = std::max<int64_t>(utime, 0);
  return Json{{"sec", us / 1000000}, {"nsec", (us % 1000000) * 1000}};
}
Json vec3(double x, double y, double z) { return Json{{"x", x}, {"y", y}, {"z", z}}; }
Json vec3(const Eigen::Vector3d& v) { return vec3(v.x(), v.y(), v.z()); }
Json quat(const Eigen::Quaterniond& q) { return Json{{"x", q.x()}, {"y", q.y()}, {"z", q.z()}, {"w", q.w()}}; }
Json pose(const Eigen::Vector3d& p, const Eigen::Quaterniond& q = Eigen::Quaterniond::Identity()) {
  return Json{{"position", vec3(p)}, {"orientation", quat(q)}};
}
Json color(double r, double g, double b, double a = 1) { return Json{{"r", r}, {"g", g}, {"b", b}, {"a", a}}; }
Eigen::Vector3d vec(const double* p) { return {p[0], p[1], p[2]}; }
Eigen::Quaterniond quat_wxyz(const double* q) { return Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized(); }

/// The viewer frame of a map frame that an output names (fused_pose_t.frame, trajectory_t.frame, landmark_map_t.frame):
/// "<name>/map", or the root "map" itself for an empty name (logs from before fleets).  Not "<name>": that is the
/// body's own frame, and a fleet frame is named by a body.
std::string map_frame_id(const std::string& frame) { return frame.empty() ? "map" : frame + "/map"; }

/// A SceneEntity in `frame_id` with every primitive list present (the schema requires them all) and empty.
Json entity(int64_t utime, const std::string& id, const std::string& frame_id = "map") {
  Json e{
      {"timestamp", stamp(utime)}, {"frame_id", frame_id},     {"id", id}, {"lifetime", Json{{"sec", 0}, {"nsec", 0}}},
      {"frame_locked", false},     {"metadata", Json::array()}};
  for (const char* k : {"arrows", "cubes", "spheres", "cylinders", "lines", "triangles", "texts", "models"})
    e[k] = Json::array();
  return e;
}
Json scene_update(Json entities, Json deletions = Json::array()) {
  return Json{{"deletions", std::move(deletions)}, {"entities", std::move(entities)}};
}
Json deletion(int64_t utime, const std::string& id) {
  constexpr int kMatchingId = 0;
  return Json{{"timestamp", stamp(utime)}, {"type", kMatchingId}, {"id", id}};
}
Json text(const Eigen::Vector3d& at, const std::string& s, const Json& c) {
  return Json{{"pose", pose(at)},        {"billboard", true}, {"font_size", 14.0},
              {"scale_invariant", true}, {"color", c},        {"text", s}};
}
Json line(int type, const Json& points, double thickness, const Json& c) {
  return Json{{"type", type},
              {"pose", pose(Eigen::Vector3d::Zero())},
              {"thickness", thickness},
              {"scale_invariant", false},
              {"points", points},
              {"color", c},
              {"colors", Json::array()},
              {"indices", Json::array()}};
}
Json sphere(const Eigen::Vector3d& at, const Eigen::Vector3d& size, const Json& c,
            const Eigen::Quaterniond& q = Eigen::Quaterniond::Identity()) {
  return Json{{"pose", pose(at, q)}, {"size", vec3(size)}, {"color", c}};
}
constexpr int kLineStrip = 0, kLineList = 2;

int estimator_rank(const std::string& e) {  // higher is better: the body's frame follows its best estimator
  return e == "graph" ? 4 : e == "ekf" ? 3 : e == "pf" ? 2 : e == "dead_reckoning" ? 1 : 0;
}

/// The 95 % ellipsoid of a 3x3 covariance: its diameters along the principal axes and their orientation.
void ellipsoid(const double* cov, Eigen::Vector3d& size, Eigen::Quaterniond& q) {
  const Eigen::Matrix3d c = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(cov);
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(0.5 * (c + c.transpose()));
  Eigen::Matrix3d axes = es.eigenvectors();
  if (axes.determinant() < 0) axes.col(2) = -axes.col(2);
  constexpr double kChi2_3dof_95 = 7.814727903251178;
  for (int i = 0; i < 3; ++i) size[i] = 2 * std::sqrt(kChi2_3dof_95 * std::max(es.eigenvalues()[i], 0.0));
  q = Eigen::Quaterniond(axes);
}

template <class Msg>
bool decode(const uint8_t* data, size_t size, Msg& m) {
  return !runtime::safe_decode(data, size, m);
}

}  // namespace

const TopicSchema* topic_schema(const std::string& name) {
  static const std::map<std::string, TopicSchema> schemas = [] {
    std::map<std::string, TopicSchema> s;
    for (const auto& t : lcm_json_types()) s[t.name] = {t.name, "jsonschema", t.schema};
    for (const auto& [n, text] : foxglove_schema_texts()) s[n] = {n, "jsonschema", text};
    return s;
  }();
  const auto it = schemas.find(name);
  return it == schemas.end() ? nullptr : &it->second;
}

namespace {

/// Which outputs are in which map frame now, for the frame list on /sextant/frames.  A user is one output stream of a
/// body: one of its estimators' poses, its trajectory, its place in a landmark map.
class FrameUsers {
 public:
  using User = std::pair<std::string, std::string>;  // (body, what)
  /// Records that `user` is in `frame` now (an empty frame is "map" itself, not listed); true when that changed the
  /// frames or who is in them.
  bool use(const User& user, const std::string& frame) {
    auto [it, fresh] = frame_of_.try_emplace(user, frame);
    if (!fresh) {
      if (it->second == frame) return false;
      leave(user, it->second);
      it->second = frame;
    }
    if (!frame.empty()) users_[frame].insert(user);
    return true;
  }
  /// Each map frame in use (by name) with its users.
  const std::map<std::string, std::set<User>>& frames() const { return users_; }

 private:
  void leave(const User& user, const std::string& frame) {
    const auto f = users_.find(frame);
    if (f == users_.end()) return;
    f->second.erase(user);
    if (f->second.empty()) users_.erase(f);
  }
  std::map<User, std::string> frame_of_;
  std::map<std::string, std::set<User>> users_;
};

/// The chunks of one landmark map publication (landmark_map_t.lcm: chunks 0 .. num_chunks - 1 of one utime).
struct MapAssembly {
  int64_t utime = std::numeric_limits<int64_t>::min();
  int32_t num_chunks = 0;
  bool complete = false;
  std::set<int32_t> chunks;
  std::vector<sextant::map_landmark_t> landmarks;
};

}  // namespace

/// The Foxglove views and the state they need.
struct TopicMapper::Views {
  TopicMapperOptions options;
  struct BodyPose {
    int rank = 0;
    Eigen::Vector3d position = Eigen::Vector3d::Zero();
    Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
    std::string frame;  // the map frame of the pose
  };
  struct TrajectoryView {
    engine::TrajectoryRebuild rebuild;
    std::string frame;  // of the latest message: the frame its keyframes are in
  };
  std::map<std::string, BodyPose> bodies;  // by source: its best estimator's latest pose
  std::map<std::pair<std::string, std::string>, TrajectoryView> trajectories;  // by (sender, source)
  std::map<std::pair<std::string, std::string>, MapAssembly> map_assemblies;   // by (sender, frame)
  std::map<std::string, int64_t> map_groups;  // by map frame: the landmark entities drawn for it
  FrameUsers frame_users;
  int64_t frames_utime = std::numeric_limits<int64_t>::min();  // when /sextant/frames went out last
  Json pending_transforms = Json::array();                     // batch_frame_transforms: gathered for the next flush
  std::set<std::string> placed;  // map frames whose transform from "map" is in pending_transforms

  void out(std::vector<ViewerMessage>& o, std::string topic, const char* schema, const Json& j) {
    o.push_back({std::move(topic), topic_schema(schema), "json", "", j.dump()});
  }

  static Json transform(int64_t utime, const std::string& parent, const std::string& child, const Eigen::Vector3d& p,
                        const Eigen::Quaterniond& q) {
    return Json{{"timestamp", stamp(utime)},
                {"parent_frame_id", parent},
                {"child_frame_id", child},
                {"translation", vec3(p)},
                {"rotation", quat(q)}};
  }

  /// map -> <frame>/map, identity, once in each /tf message whose transforms or scene hang from that map frame: every
  /// map frame has a path to the display frame "map" (see the header: how fleet frames appear).
  void place(const std::string& frame, int64_t utime) {
    if (frame.empty() || !placed.insert(frame).second) return;
    pending_transforms.push_back(
        transform(utime, "map", map_frame_id(frame), Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity()));
  }

  /// `user` is in `frame` now: /sextant/frames goes out when the frames or their users changed, and at least once
  /// per second of data time while there are any (a viewer that connects later gets it too).
  void use_frame(const FrameUsers::User& user, const std::string& frame, int64_t utime, std::vector<ViewerMessage>& o) {
    const bool changed = frame_users.use(user, frame);
    if (frame_users.frames().empty()) return;
    constexpr int64_t kPeriod = 1'000'000;
    if (changed || utime >= frames_utime + kPeriod || utime < frames_utime - kPeriod) frame_list(utime, o);
  }

  /// One text in "map" listing the map frames: the first by name is the fleet's frame (a join moves the frame of the
  /// later name into the earlier one), the others are unplaced, drawn at map's origin.
  void frame_list(int64_t utime, std::vector<ViewerMessage>& o) {
    const auto& frames = frame_users.frames();
    std::string lines;
    for (const auto& [frame, users] : frames) {
      std::set<std::string> names;
      for (const auto& u : users) names.insert(u.first);
      std::string bodies;
      for (const auto& b : names) bodies += (bodies.empty() ? "" : ", ") + b;
      lines += (lines.empty() ? "" : "\n") + map_frame_id(frame) +
               (frame == frames.begin()->first ? " = map" : " unplaced: drawn at map's origin") + " (" + bodies + ")";
    }
    Json e = entity(utime, "frames");
    e["texts"].push_back(text(Eigen::Vector3d::Zero(), lines, color(1, 1, 1)));
    out(o, "/sextant/frames", "foxglove.SceneUpdate", scene_update(Json::array({e})));
    frames_utime = utime;
  }

  void fused_pose(const sextant::fused_pose_t& m, std::vector<ViewerMessage>& o) {
    const Eigen::Vector3d p = vec(m.position);
    const Eigen::Quaterniond q = quat_wxyz(m.orientation);
    const std::string frame = map_frame_id(m.frame);
    out(o, "/sextant/" + m.source + "/" + m.estimator + "/pose", "foxglove.PoseInFrame",
        Json{{"timestamp", stamp(m.utime)}, {"frame_id", frame}, {"pose", pose(p, q)}});
    place(m.frame, m.utime);
    pending_transforms.push_back(transform(m.utime, frame, m.source + "/" + m.estimator, p, q));
    auto& body = bodies[m.source];
    if (estimator_rank(m.estimator) >= body.rank) {
      body = {estimator_rank(m.estimator), p, q, m.frame};
      pending_transforms.push_back(transform(m.utime, frame, m.source, p, q));
    }
    use_frame({m.source, m.estimator}, m.frame, m.utime, o);
    if (!options.batch_frame_transforms) flush(o);
  }

  /// On Foxglove's Map panel: the body's position on the Earth, with its ENU covariance.
  void geo_pose(const sextant::geo_pose_t& m, std::vector<ViewerMessage>& o) {
    Json covariance = Json::array();
    for (double v : m.position_covariance) covariance.push_back(v);
    out(o, "/sextant/" + m.source + "/" + m.estimator + "/fix", "foxglove.LocationFix",
        Json{{"timestamp", stamp(m.utime)},
             {"frame_id", m.source},
             {"latitude", m.latitude},
             {"longitude", m.longitude},
             {"altitude", m.altitude},
             {"position_covariance", std::move(covariance)},
             {"position_covariance_type", 3}});  // KNOWN: the estimator's full covariance
  }

  void flush(std::vector<ViewerMessage>& o) {
    if (pending_transforms.empty()) return;
    out(o, "/tf", "foxglove.FrameTransforms", Json{{"transforms", std::move(pending_transforms)}});
    pending_transforms = Json::array();
    placed.clear();
  }

  /// A body's trajectory is drawn in segments of kSegment keyframe ids (entity "<source>/trajectory/<k>", each
  /// strip starting at the last keyframe before its range so that the strips join), and a message redraws only the
  /// segments whose keyframes it touched: a lifelong trajectory of thousands of keyframes costs a message what its
  /// changes cost, not the whole trajectory.
  static constexpr int64_t kSegment = 256;

  Json trajectory_segment(const TrajectoryView& view, const std::string& source, int64_t segment, int64_t utime) {
    const auto& kfs = view.rebuild.keyframes();
    Json points = Json::array();
    auto it = kfs.lower_bound(segment * kSegment);
    if (it != kfs.begin()) points.push_back(vec3(std::prev(it)->second.pose.position));
    for (; it != kfs.end() && it->first < (segment + 1) * kSegment; ++it)
      points.push_back(vec3(it->second.pose.position));
    Json e = entity(utime, source + "/trajectory/" + std::to_string(segment), map_frame_id(view.frame));
    if (points.size() >= 2) e["lines"].push_back(line(kLineStrip, points, 0.05, color(0.1, 0.6, 1.0)));
    return e;
  }

  /// The segments a message changes: those of the keyframes it carries, removes or (a snapshot) may erase, each
  /// with the next one (whose strip starts at its end); all of them when the trajectory moved to another map frame
  /// (trajectory_t.frame: every keyframe is in the message's frame now).
  std::set<int64_t> touched_segments(const TrajectoryView& view, const engine::Trajectory& t,
                                     const std::string& frame) {
    std::set<int64_t> touched;
    auto touch = [&](int64_t id) {
      touched.insert(id / kSegment);
      touched.insert(id / kSegment + 1);
    };
    const auto& held = view.rebuild.keyframes();
    if (frame != view.frame && !held.empty())
      for (int64_t s = held.begin()->first / kSegment; s <= held.rbegin()->first / kSegment + 1; ++s) touched.insert(s);
    if (t.kind == engine::Trajectory::Kind::kSnapshot)  // the keyframes it may erase (its range can be open-ended)
      for (auto it = held.lower_bound(t.range_first); it != held.end() && it->first <= t.range_last; ++it)
        touch(it->first);
    for (const auto& k : t.keyframes) touch(k.id);
    for (int64_t id : t.removed_ids) touch(id);
    return touched;
  }

  void trajectory(const sextant::trajectory_t& m, std::vector<ViewerMessage>& o) {
    auto& view = trajectories[{m.sender, m.source}];
    const auto t = runtime::to_output(m);
    const std::set<int64_t> touched = touched_segments(view, t, m.frame);
    view.rebuild.add(t);
    view.frame = m.frame;
    Json entities = Json::array();
    for (int64_t s : touched) entities.push_back(trajectory_segment(view, m.source, s, m.utime));
    const auto& kfs = view.rebuild.keyframes();
    if (!kfs.empty()) {
      Json label = entity(m.utime, m.source + "/trajectory/label", map_frame_id(m.frame));
      label["texts"].push_back(text(kfs.rbegin()->second.pose.position,
                                    m.source + " (" + std::to_string(kfs.size()) + " keyframes)", color(1, 1, 1)));
      entities.push_back(label);
    }
    out(o, "/sextant/trajectories", "foxglove.SceneUpdate", scene_update(entities));
    use_frame({m.source, "trajectory " + m.sender}, m.frame, m.utime, o);
    place(m.frame, m.utime);
    if (!options.batch_frame_transforms) flush(o);
  }

  /// Adds one chunk of a landmark map; the whole map, by id, once its publication's chunks are all there.
  std::optional<std::vector<sextant::map_landmark_t>> assemble(const sextant::landmark_map_t& m) {
    if (m.num_chunks < 1 || m.chunk < 0 || m.chunk >= m.num_chunks)
      throw std::runtime_error("landmark_map_t: chunk " + std::to_string(m.chunk) + " of " +
                               std::to_string(m.num_chunks));
    MapAssembly& a = map_assemblies[{m.sender, m.frame}];
    if (m.utime < a.utime || (m.utime == a.utime && a.complete)) return std::nullopt;  // older, or a repeat
    if (m.utime > a.utime || m.num_chunks != a.num_chunks) a = MapAssembly{m.utime, m.num_chunks, false, {}, {}};
    if (!a.chunks.insert(m.chunk).second) return std::nullopt;
    a.landmarks.insert(a.landmarks.end(), m.landmarks.begin(), m.landmarks.end());
    if (static_cast<int32_t>(a.chunks.size()) < a.num_chunks) return std::nullopt;
    a.complete = true;
    std::vector<sextant::map_landmark_t> whole = std::move(a.landmarks);
    a.landmarks = {};
    std::sort(whole.begin(), whole.end(), [](const auto& x, const auto& y) { return x.id < y.id; });
    return whole;
  }

  /// A map frame's landmarks as spheres and labels (their ids), in entities of kMapGroup landmarks by id
  /// ("landmark_map/<frame>/<k>"), replacing the frame's previous map whole: what it had beyond deleted.  A map of no
  /// landmarks (its frame joined another) deletes them all.
  static constexpr size_t kMapGroup = 1024;

  void landmark_map(const sextant::landmark_map_t& m, std::vector<ViewerMessage>& o) {
    const auto landmarks = assemble(m);
    if (!landmarks) return;
    const std::string frame = map_frame_id(m.frame), prefix = "landmark_map/" + m.frame + "/";
    Json entities = Json::array(), deletions = Json::array();
    const int64_t groups = static_cast<int64_t>((landmarks->size() + kMapGroup - 1) / kMapGroup);
    for (int64_t g = 0; g < groups; ++g) {
      Json e = entity(m.utime, prefix + std::to_string(g), frame);
      const size_t end = std::min(landmarks->size(), static_cast<size_t>(g + 1) * kMapGroup);
      for (size_t i = static_cast<size_t>(g) * kMapGroup; i < end; ++i) {
        const auto& l = (*landmarks)[i];
        e["spheres"].push_back(sphere(vec(l.position), Eigen::Vector3d::Constant(0.5), color(1.0, 0.55, 0.0, 0.9)));
        e["texts"].push_back(text(vec(l.position), std::to_string(l.id), color(1.0, 0.7, 0.3)));
      }
      entities.push_back(std::move(e));
    }
    int64_t& drawn = map_groups[m.frame];
    for (int64_t g = groups; g < drawn; ++g) deletions.push_back(deletion(m.utime, prefix + std::to_string(g)));
    drawn = groups;
    if (!entities.empty() || !deletions.empty())
      out(o, "/sextant/landmark_map", "foxglove.SceneUpdate", scene_update(entities, deletions));
    for (const auto& body : m.bodies) use_frame({body, "landmark map " + m.sender}, m.frame, m.utime, o);
    if (groups == 0) return;
    place(m.frame, m.utime);
    if (!options.batch_frame_transforms) flush(o);
  }

  void targets(const sextant::targets_t& m, std::vector<ViewerMessage>& o) {
    Json e = entity(m.utime, "targets/" + m.sender);
    for (size_t i = 0; i < m.targets.size(); ++i) {
      Eigen::Vector3d size;
      Eigen::Quaterniond q;
      ellipsoid(m.targets[i].covariance, size, q);
      const Eigen::Vector3d p = vec(m.targets[i].position);
      e["spheres"].push_back(sphere(p, size, color(1.0, 0.3, 0.2, 0.5), q));
      e["texts"].push_back(text(p, "target " + std::to_string(i), color(1.0, 0.5, 0.4)));
    }
    out(o, "/sextant/targets", "foxglove.SceneUpdate", scene_update(Json::array({e})));
  }

  void bearings(const sextant::bearing_scan_t& m, std::vector<ViewerMessage>& o) {
    const Eigen::Vector3d s = vec(m.sensor_position);
    Json e = entity(m.utime, "sensor/" + std::to_string(m.sensor_id));
    e["cubes"].push_back(Json{{"pose", pose(s)}, {"size", vec3(0.6, 0.6, 0.6)}, {"color", color(0.9, 0.8, 0.1)}});
    e["texts"].push_back(text(s, "sensor " + std::to_string(m.sensor_id), color(0.9, 0.8, 0.1)));
    Json rays = Json::array();
    for (const auto& d : m.detections) {
      const Eigen::Vector3d dir(std::cos(d.elevation) * std::cos(d.azimuth),
                                std::cos(d.elevation) * std::sin(d.azimuth), std::sin(d.elevation));
      rays.push_back(vec3(s));
      rays.push_back(vec3(s + options.bearing_ray_length_m * dir));
    }
    e["lines"].push_back(line(kLineList, rays, 0.03, color(0.9, 0.8, 0.1, 0.7)));
    out(o, "/sextant/bearings", "foxglove.SceneUpdate", scene_update(Json::array({e})));
  }

  void landmarks(const sextant::landmarks_t& m, std::vector<ViewerMessage>& o) {
    const auto body = bodies.find(m.source);
    if (body == bodies.end()) return;  // no pose of the body yet: nowhere to place its sightings
    // In the map frame of the body's pose.
    const Eigen::Isometry3d map_body = Eigen::Translation3d(body->second.position) * body->second.orientation;
    const Eigen::Isometry3d map_sensor =
        map_body * (Eigen::Translation3d(vec(m.sensor_position)) * quat_wxyz(m.sensor_orientation));
    Json e = entity(m.utime, m.source + "/sightings", map_frame_id(body->second.frame));
    Json rays = Json::array();
    for (const auto& s : m.observations) {
      const double el = m.planar ? 0.0 : s.elevation;
      const Eigen::Vector3d in_sensor = s.range * Eigen::Vector3d(std::cos(el) * std::cos(s.azimuth),
                                                                  std::cos(el) * std::sin(s.azimuth), std::sin(el));
      const Eigen::Vector3d p = map_sensor * in_sensor;
      rays.push_back(vec3(map_sensor.translation()));
      rays.push_back(vec3(p));
      e["spheres"].push_back(sphere(p, Eigen::Vector3d::Constant(0.3), color(0.3, 1.0, 0.3)));
    }
    e["lines"].push_back(line(kLineList, rays, 0.02, color(0.3, 1.0, 0.3, 0.6)));
    out(o, "/sextant/landmarks", "foxglove.SceneUpdate", scene_update(Json::array({e})));
  }

  void truth(const sextant::truth_t& m, std::vector<ViewerMessage>& o) {
    if (m.kind == "robot") {
      out(o, "/sextant/" + m.source + "/truth/pose", "foxglove.PoseInFrame",
          Json{{"timestamp", stamp(m.utime)},
               {"frame_id", "map"},
               {"pose", pose(vec(m.position), quat_wxyz(m.orientation))}});
      return;
    }
    const std::string id = m.kind + " " + std::to_string(m.id);
    Json e = entity(m.utime, "truth/" + id);
    e["spheres"].push_back(sphere(vec(m.position), Eigen::Vector3d::Constant(0.5), color(0.7, 0.7, 0.7, 0.8)));
    e["texts"].push_back(text(vec(m.position), id, color(0.8, 0.8, 0.8)));
    out(o, "/sextant/truth", "foxglove.SceneUpdate", scene_update(Json::array({e})));
  }

  /// The Foxglove views of one message of a known type.
  void add(const LcmJsonType& type, const uint8_t* data, size_t size, std::vector<ViewerMessage>& o) {
    if (type.name == "sextant.fused_pose_t") {
      sextant::fused_pose_t m;
      if (decode(data, size, m)) fused_pose(m, o);
    } else if (type.name == "sextant.geo_pose_t") {
      sextant::geo_pose_t m;
      if (decode(data, size, m)) geo_pose(m, o);
    } else if (type.name == "sextant.trajectory_t") {
      sextant::trajectory_t m;
      if (decode(data, size, m)) trajectory(m, o);
    } else if (type.name == "sextant.targets_t") {
      sextant::targets_t m;
      if (decode(data, size, m)) targets(m, o);
    } else if (type.name == "sextant.bearing_scan_t") {
      sextant::bearing_scan_t m;
      if (decode(data, size, m)) bearings(m, o);
    } else if (type.name == "sextant.landmarks_t") {
      sextant::landmarks_t m;
      if (decode(data, size, m)) landmarks(m, o);
    } else if (type.name == "sextant.landmark_map_t") {
      sextant::landmark_map_t m;
      if (decode(data, size, m)) landmark_map(m, o);
    } else if (type.name == "sextant.truth_t") {
      sextant::truth_t m;
      if (decode(data, size, m)) truth(m, o);
    }
  }
};

TopicMapper::TopicMapper(TopicMapperOptions options) : options_(options), views_(std::make_unique<Views>()) {
  views_->options = options;
}
TopicMapper::~TopicMapper() = default;
void TopicMapper::flush(std::vector<ViewerMessage>& out) { views_->flush(out); }
TopicMapper::TopicMapper(TopicMapper&&) noexcept = default;
TopicMapper& TopicMapper::operator=(TopicMapper&&) noexcept = default;

void TopicMapper::map(const std::string& channel, const uint8_t* data, size_t size, std::vector<ViewerMessage>& out) {
  ++counts_.messages;
  const LcmJsonType* type = lcm_json_type_of(data, size);
  std::optional<std::string> json;
  if (type) {
    if (auto j = type->decode(data, size, nullptr)) {
      try {
        json = j->dump();  // throws on a string that is not UTF-8
        if (options_.check_round_trip) {
          const auto bytes = type->encode(*j);
          if (bytes.size() != size || !std::equal(bytes.begin(), bytes.end(), data)) json.reset();
        }
      } catch (const std::exception&) {
        json.reset();
      }
    }
  }
  if (!json) {
    ++counts_.raw;
    if (options_.keep_raw)
      out.push_back(
          {"lcm_raw/" + channel, nullptr, "lcm", channel, std::string(reinterpret_cast<const char*>(data), size)});
    return;
  }
  out.push_back({channel, topic_schema(type->name), "json", channel, std::move(*json)});
  try {
    views_->add(*type, data, size, out);
  } catch (const std::exception&) {
    ++counts_.view_errors;
  }
}

}  // namespace sextant::viewer
