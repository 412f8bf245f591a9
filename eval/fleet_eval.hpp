#pragma once
// A fleet's map against the ground truth under one alignment: every robot's final keyframes (associated with its
// ground truth by time, associate() of trajectory_eval.hpp) and the landmarks (by id) are aligned together by one
// rigid transform (align_points: SE(2) for a planar fleet, SE(3) otherwise; no scale), so the figures say whether the
// robots and the landmarks are in one consistent frame, not only whether each trajectory has the right shape:
//  - per robot, the ATE of its keyframes under the fleet's alignment (fleet-frame ATE), and under its own alignment
//    (the usual ATE, for comparison: a robot whose frame is off by a rigid transform has a large fleet-frame ATE and
//    a small own one);
//  - the landmarks' position error under the fleet's alignment.
// Every point weighs the same in the alignment (a robot with more keyframes pulls it harder).
#include "eval/trajectory_eval.hpp"

#include <map>
#include <string>

namespace sextant::tools {

struct FleetEvaluationOptions {
  bool planar = true;            // SE(2) alignment (rotation about z, translation in x, y)
  double max_difference = 0.02;  // association window, seconds
};

struct FleetRobotError {
  ErrorStatistics fleet;  // |A p - q| over the robot's matched keyframes, A the fleet's alignment; metres
  ErrorStatistics own;    // the same under the robot's own alignment; metres
  size_t matched = 0, keyframes = 0;
};

struct FleetEvaluation {
  RigidAlignment alignment;  // estimate -> ground truth
  std::map<std::string, FleetRobotError> robots;
  ErrorStatistics landmarks;  // |A l - l_true| over the landmarks with a true position; metres
  size_t landmarks_estimated = 0;
};

/// `keyframes` and `landmarks` are the estimate in one map frame; `truth` and `landmark_truth` the ground truth.
/// A robot without ground truth, or with fewer than 2 matched keyframes, is left out (not in `robots`), and so is a
/// landmark without a true position.  Throws std::invalid_argument when fewer than 2 points match in all.
FleetEvaluation evaluate_fleet(const std::map<std::string, std::vector<StampedPose>>& keyframes,
                               const LandmarkPositions& landmarks,
                               const std::map<std::string, std::vector<StampedPose>>& truth,
                               const LandmarkPositions& landmark_truth, const FleetEvaluationOptions& options = {});

}  // namespace sextant::tools
