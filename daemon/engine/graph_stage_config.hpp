#pragma once
#include "daemon/engine/fleet_exchange_options.hpp"
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
  /// Daemon only (daemon/runtime/odometry_batcher.hpp): a body's odometry waiting for the stage's thread is batched,
  /// one queue slot per batch instead of per message; the stage still handles every message on its own.
  bool coalesce_odometry = true;
  int odometry_batch_max = 256;            // messages per batch (a full batch takes one more queue slot)
  int odometry_waiting_max = 16384;        // messages of one body waiting in batches (about 1.1 kB each)
  int odometry_waiting_total_max = 65536;  // messages of all bodies waiting in batches
  TrajectoryFeedOptions trajectory;        // what TRAJECTORY carries and how often (trajectory_feed.hpp)
  /// engine.graph.fleet.exchange: one daemon per robot, exchanging graph contributions on FLEET (fleet_exchange.hpp).
  FleetExchangeOptions fleet_exchange;
};

}  // namespace sextant::engine
