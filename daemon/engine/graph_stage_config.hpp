#pragma once
#include "estimators/keyframe/keyframe_selector.hpp"
#include "estimators/keyframe/loop_proposals.hpp"

#include <string>

namespace sextant::engine {

/// Landmark sightings in the graph back end (graph_stage.hpp): sightings with an id become point landmarks of the
/// observing body and range/bearing factors on its keyframes.
struct GraphLandmarkOptions {
  bool enabled = true;
  bool robust = true;                   // the smoother's kernel (GraphConfig::robust, kernel_width) applies to them
  double gate_probability = 0.999;      // chi-square gate of a sighting of a known landmark against the estimate
  double gate_odometry_scale = 3.0;     // the odometry's standard deviations are taken this many times larger in the
                                        // gate (the odometry between keyframe and sighting; biases are not in it)
  int max_waiting = 256;                // sighting messages per body ahead of its odometry, kept until it gets there
};

/// The graph back end (source B): keyframes by motion magnitude, loop proposals on MATCH_REQUESTS, loop closures
/// from LOOP_CLOSURES, landmark sightings from LANDMARKS, incremental smoothing, TRAJECTORY after each optimization
/// and FUSED_POSE "graph" at the odometry rate.
struct GraphConfig {
  bool enabled = true;
  KeyframeSelectorOptions keyframes;   // k1, k2 (motion magnitude, metres/radians combined) and the weights
  bool propose_loops = true;           // publish MATCH_REQUESTS for each new keyframe
  LoopProposalOptions proposals;       // n1 local, n2 random (-1: 2 n1), seed
  std::string robust = "dcs";          // kernel on loop closures (and landmark sightings): none | huber | cauchy | dcs
  double kernel_width = 1.0;           // Huber/Cauchy delta or DCS phi
  double loop_gate_probability = 0.999;  // chi-square consistency gate of a loop against the current estimate
  double loop_gate_odometry_scale = 3.0; // the odometry's standard deviations are taken this many times larger in the
                                         // gate (odometry covariances are optimistic: biases are not in them)
  double loop_time_tolerance_s = 1.0;    // a loop's times must be this close to keyframes' times (odometry bridges the gap)
  int odometry_history = 100000;         // odometry poses kept per body to bridge loop times to keyframes
  bool coalesce_odometry = true;         // daemon: a body's odometry waiting for the stage is coalesced instead of
                                         // taking one queue slot per message (odometry_coalescer.hpp)
  int odometry_batch_max = 256;          // messages a coalesced batch keeps unmerged (keyframe candidates, sighting times)
  double relinearize_translation = 0.1;   // m
  double relinearize_rotation = 0.1;      // rad
  double min_increment_variance = 1e-10;
  int trajectory_max_keyframes = 4096;    // TRAJECTORY carries at most this many (the newest) keyframes
  GraphLandmarkOptions landmarks;
};

}  // namespace sextant::engine
