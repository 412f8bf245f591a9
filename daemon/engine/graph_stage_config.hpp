#pragma once
#include "daemon/engine/trajectory_feed.hpp"
#include "estimators/slam/slam_options.hpp"

namespace sextant::engine {

/// The robust kernels' widths per kind of body, for loops and for sightings (estimators/slam/slam_options.hpp).
using slam::kernel_width_for;
using slam::sighting_kernel_width_for;

/// The graph back end: keyframes by motion magnitude, loop proposals on MATCH_REQUESTS, loop closures
/// from LOOP_CLOSURES, landmark sightings from LANDMARKS, incremental smoothing, TRAJECTORY after each optimization
/// and FUSED_POSE "graph" at the odometry rate.  The SLAM layer's options (estimators/slam/slam_options.hpp: keyframes,
/// loop proposals and gating, the odometry history, landmarks, the smoother, lifelong) and the stage's own.
struct GraphConfig : slam::SlamOptions {
  bool enabled = true;
  bool coalesce_odometry = true;         // daemon: a body's odometry waiting for the stage is coalesced instead of
                                         // taking one queue slot per message (odometry_coalescer.hpp)
  int odometry_batch_max = 256;          // messages a coalesced batch keeps unmerged (keyframe candidates, sighting times)
  TrajectoryFeedOptions trajectory;       // what TRAJECTORY carries and how often (trajectory_feed.hpp)
};

}  // namespace sextant::engine
