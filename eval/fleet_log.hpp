#pragma once
// A fleet's estimate and ground truth read from logs and files, for evaluate_fleet (fleet_eval.hpp):
//  - a replay's output log (`sextant replay ... --out-log`): each body's final trajectory rebuilt from TRAJECTORY by
//    the subscriber's rule (TrajectoryRebuild, trajectory_t.lcm), with the map frame its last message names; the
//    online FUSED_POSE of one estimator per body; the last LANDMARK_MAP per map frame;
//  - the ground truth: the GROUND_TRUTH messages (truth_t) of a log, or files PREFIX + BODY + ".txt" (TUM) and
//    PREFIX + "landmarks.txt" (write_landmarks' format), as `sextant convert mrclam --robots` and
//    `sextant simulate --robots` write them.
#include "eval/trajectory_io.hpp"

#include <map>
#include <string>
#include <vector>

namespace sextant::tools {

using BodyTrajectories = std::map<std::string, std::vector<StampedPose>>;

struct FleetOutput {
  BodyTrajectories keyframes;                 // final keyframes per body, in time order
  std::map<std::string, std::string> frames;  // per body: the map frame of its last TRAJECTORY (empty: unnamed)
  BodyTrajectories fused;                     // FUSED_POSE of the chosen estimator per body, as published
  std::map<std::string, std::vector<std::string>> fused_frames;  // per body and fused pose: its map frame
  std::map<std::string, LandmarkPositions> maps;                 // the last LANDMARK_MAP per map frame
};

/// Reads an output log; FUSED_POSE messages of estimators other than `estimator` are skipped.  Throws
/// std::runtime_error when the log cannot be read or a message does not decode.
FleetOutput read_fleet_output(const std::string& out_log, const std::string& estimator);

/// Adds `from`'s bodies and map frames to `into` (a body or frame in both: `from`'s), e.g. single-robot replays
/// evaluated together.
void merge_into(FleetOutput& into, FleetOutput&& from);

struct FleetTruth {
  BodyTrajectories robots;  // per body, sorted by time
  LandmarkPositions landmarks;
};

/// The ground truth in a log's GROUND_TRUTH channel: truth_t "robot" poses per source, "landmark" positions by id.
FleetTruth read_truth_log(const std::string& log);

/// The ground truth in files: PREFIX + BODY + ".txt" for each of `bodies` that has one (TUM), and PREFIX +
/// "landmarks.txt" when it exists.
FleetTruth read_truth_files(const std::string& prefix, const std::vector<std::string>& bodies);

}  // namespace sextant::tools
