#include "eval/fleet_log.hpp"

#include "daemon/engine/trajectory_rebuild.hpp"
#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/lcm_log.hpp"

#include <sextant/fused_pose_t.hpp>
#include <sextant/landmark_map_t.hpp>
#include <sextant/trajectory_t.hpp>
#include <sextant/truth_t.hpp>

#include <algorithm>
#include <filesystem>
#include <stdexcept>

namespace sextant::tools {
namespace {

template <class Message>
Message decoded(const runtime::LogRecord& r) {
  Message m;
  if (m.decode(r.data.data(), 0, static_cast<int>(r.data.size())) < 0)
    throw std::runtime_error("a " + r.channel + " message at " + std::to_string(r.timestamp) + " does not decode");
  return m;
}

engine::Pose pose_of(const double position[3], const double orientation[4]) {
  engine::Pose p;
  p.position = {position[0], position[1], position[2]};
  p.orientation = Eigen::Quaterniond(orientation[0], orientation[1], orientation[2], orientation[3]).normalized();
  return p;
}

// One chunk of a LANDMARK_MAP publication: chunk 0 starts the frame's map afresh, the last chunk completes it (a
// frame published with no landmark left, it joined another).
void add_map_chunk(const sextant::landmark_map_t& m, std::map<std::string, LandmarkPositions>& pending,
                   std::map<std::string, LandmarkPositions>& maps) {
  auto& p = pending[m.frame];
  if (m.chunk == 0) p.clear();
  for (const auto& l : m.landmarks) p[l.id] = Eigen::Vector3d(l.position[0], l.position[1], l.position[2]);
  if (m.chunk + 1 < m.num_chunks) return;
  if (m.total_landmarks == 0)
    maps.erase(m.frame);
  else
    maps[m.frame] = p;
}

}  // namespace

FleetOutput read_fleet_output(const std::string& out_log, const std::string& estimator) {
  FleetOutput out;
  std::map<std::string, engine::TrajectoryRebuild> rebuilds;
  std::map<std::string, LandmarkPositions> pending;  // per frame: the chunks of its publication so far
  for (const auto& r : runtime::LogReader::read_all(out_log)) {
    if (r.channel == "TRAJECTORY") {
      const auto m = decoded<sextant::trajectory_t>(r);
      rebuilds[m.source].add(runtime::to_output(m));
      out.frames[m.source] = m.frame.empty() ? m.source : m.frame;
    } else if (r.channel == "LANDMARK_MAP") {
      add_map_chunk(decoded<sextant::landmark_map_t>(r), pending, out.maps);
    } else if (r.channel.rfind("FUSED_POSE", 0) == 0) {  // FUSED_POSE (the primary) or FUSED_POSE_<ESTIMATOR>
      const auto m = decoded<sextant::fused_pose_t>(r);
      if (m.estimator != estimator) continue;
      out.fused[m.source].push_back({m.utime * 1e-6, pose_of(m.position, m.orientation)});
      out.fused_frames[m.source].push_back(m.frame.empty() ? m.source : m.frame);
    }
  }
  for (const auto& [body, rebuild] : rebuilds) {
    auto& poses = out.keyframes[body];
    for (const auto& [id, k] : rebuild.keyframes()) poses.push_back({k.utime * 1e-6, k.pose});
    std::sort(poses.begin(), poses.end(), [](const StampedPose& a, const StampedPose& b) { return a.t < b.t; });
  }
  return out;
}

void merge_into(FleetOutput& into, FleetOutput&& from) {
  for (auto& [body, poses] : from.keyframes) into.keyframes[body] = std::move(poses);
  for (auto& [body, frame] : from.frames) into.frames[body] = std::move(frame);
  for (auto& [body, poses] : from.fused) into.fused[body] = std::move(poses);
  for (auto& [body, frames] : from.fused_frames) into.fused_frames[body] = std::move(frames);
  for (auto& [frame, map] : from.maps) into.maps[frame] = std::move(map);
}

FleetTruth read_truth_log(const std::string& log) {
  FleetTruth t;
  for (const auto& r : runtime::LogReader::read_all(log)) {
    if (r.channel != "GROUND_TRUTH") continue;
    const auto m = decoded<sextant::truth_t>(r);
    if (m.kind == "robot")
      t.robots[m.source].push_back({m.utime * 1e-6, pose_of(m.position, m.orientation)});
    else if (m.kind == "landmark")
      t.landmarks[m.id] = Eigen::Vector3d(m.position[0], m.position[1], m.position[2]);
  }
  for (auto& [body, poses] : t.robots)
    std::stable_sort(poses.begin(), poses.end(), [](const StampedPose& a, const StampedPose& b) { return a.t < b.t; });
  return t;
}

FleetTruth read_truth_files(const std::string& prefix, const std::vector<std::string>& bodies) {
  FleetTruth t;
  for (const auto& body : bodies)
    if (std::filesystem::exists(prefix + body + ".txt")) t.robots[body] = read_tum(prefix + body + ".txt");
  if (std::filesystem::exists(prefix + "landmarks.txt")) t.landmarks = read_landmarks(prefix + "landmarks.txt");
  return t;
}

}  // namespace sextant::tools
