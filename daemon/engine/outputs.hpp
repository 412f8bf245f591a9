#pragma once
// What engine stages produce; the daemon publishes these (daemon/runtime/codec.hpp), replay writes them to files.
#include "daemon/engine/events.hpp"

namespace sextant::engine {

/// Best current pose of a body in the map frame (fused_pose_t).
struct FusedPose {
  int64_t utime = 0;
  std::string source;
  std::string estimator;  // "dead_reckoning", "ekf", "pf", "inertial", "graph"
  std::string frame;      // the map frame, named by its root body (fused_pose_t.frame); empty: the body itself
  bool planar = false;
  Pose pose;
  Matrix6 covariance = Matrix6::Zero();
};

/// A FusedPose on the Earth (geo_pose_t, channel FUSED_GEO), for the estimators whose map frame is the ENU plane of
/// a GNSS datum: geodetic position, orientation and position covariance in the local ENU at the body (geo_pose.hpp).
struct GeoPose {
  int64_t utime = 0;
  std::string source;
  std::string estimator;
  bool heading_known = false;                        // the map frame's heading is ENU (geo_pose_t.heading_known)
  double latitude = 0, longitude = 0, altitude = 0;  // degrees, degrees, metres above the WGS84 ellipsoid
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  // body to local ENU
  Eigen::Matrix3d position_covariance = Eigen::Matrix3d::Zero();    // m^2, local ENU
  Eigen::Vector3d datum = Eigen::Vector3d::Zero();                  // latitude, longitude, altitude of the plane
};

struct Keyframe {
  int64_t id = 0;
  int64_t utime = 0;
  Pose pose;
};

/// Optimized keyframes of a body (trajectory_t; the .lcm file says how a subscriber rebuilds the trajectory from
/// UPDATE and SNAPSHOT messages; TrajectoryFeed decides what each carries).
struct Trajectory {
  enum class Kind { kUpdate = 0, kSnapshot = 1 };
  int64_t utime = 0;
  std::string source;
  std::string estimator = "graph";
  std::string frame;  // the map frame of the keyframes (trajectory_t.frame); empty: the body itself
  double chi2 = 0;
  int iterations = 0;
  double solve_ms = 0;
  Kind kind = Kind::kUpdate;
  int64_t snapshot_id = 0;                  // kSnapshot: the cycle
  int chunk = 0, num_chunks = 0;            // kSnapshot: this chunk of the cycle
  int64_t range_first = 0, range_last = 0;  // kSnapshot: the id range the chunk is authoritative for
  int total_keyframes = 0;                  // the body's keyframes now
  std::vector<Keyframe> keyframes;
  std::vector<int64_t> removed_ids;  // kUpdate: keyframes that left the graph since the last publication
};

/// Ask a front end to match keyframe a (new) against keyframe b (match_request_t).
struct MatchRequest {
  int64_t utime = 0;
  std::string source;    // the body of keyframe a
  std::string source_b;  // the body of keyframe b; empty: source
  int64_t request_id = 0;
  std::string kind;  // "local", "random" or "fleet"
  Keyframe a, b;
};

struct Target {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  std::vector<int32_t> detection_indices;  // per sensor of Targets::sensor_ids; -1 = missed
  double cost = 0;
};

/// Association result of one scan across sensors (targets_t).
struct Targets {
  int64_t utime = 0;
  int64_t scan_id = 0;
  std::string cost_kind;
  double total_cost = 0;
  double duality_gap = 0;
  std::vector<int32_t> sensor_ids;
  std::vector<Target> targets;
};

/// The graph's landmarks in one map frame (landmark_map_t: one chunk of a publication).
struct LandmarkMap {
  struct Landmark {
    int64_t id = 0;
    Eigen::Vector3d position = Eigen::Vector3d::Zero();  // metres, map frame
    int32_t sightings = 0;
  };
  int64_t utime = 0;
  std::string frame;  // the map frame (its root body)
  std::vector<std::string> bodies;
  int chunk = 0, num_chunks = 1;
  int total_landmarks = 0;
  std::vector<Landmark> landmarks;
};

/// FleetContributions and FleetControl (fleet_events.hpp): the graph stage's contributions, heartbeats, repair
/// requests and answers for the other daemons of a fleet (FLEET, FLEET_CONTROL); the publisher stamps the sender.
using Output =
    std::variant<FusedPose, GeoPose, Trajectory, MatchRequest, Targets, LandmarkMap, FleetContributions, FleetControl>;

}  // namespace sextant::engine
