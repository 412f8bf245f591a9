#pragma once
// The kinds that name the engine's stages and the estimators they publish: typed everywhere outside the config
// reader, spelt only by the tables of stage_kinds.cpp.
#include <string>

namespace sextant::engine {

/// An estimator whose fused pose a stage publishes, and the choice of the one that goes on FUSED_POSE (config key
/// `engine.primary_estimator`); its spelling is the estimator's name (Stage::estimator(), the suffix of
/// FUSED_POSE_<ESTIMATOR>).
enum class PrimaryEstimator {
  kAuto,           // "auto": the most capable enabled stage, graph > filter > dead reckoning (never a stage's own)
  kDeadReckoning,  // "dead_reckoning"
  kEkf,            // "ekf"
  kPf,             // "pf"
  kGraph,          // "graph"
  kInertial,       // "inertial"
  kInertialGraph,  // "inertial_graph"
};
/// The kind of a config spelling; throws std::invalid_argument naming the spellings for any other name.
PrimaryEstimator primary_estimator_from_name(const std::string& name);
const char* primary_estimator_name(PrimaryEstimator estimator);

/// Which of the engine's stages a stage is (engine.cpp makes them); kOther for a stage the engine does not make
/// (a test's).  Its spelling is the stage's name on the status channel and in reports.
enum class StageKind {
  kDeadReckoning,   // "dead_reckoning" (dead_reckoning_stage.hpp)
  kFilter,          // "filter" (filter_stage.hpp)
  kParticleFilter,  // "particle_filter" (particle_filter_stage.hpp)
  kGraph,           // "graph": the graph back end (graph_stage.hpp)
  kGraphPose,       // "graph_pose": the graph's fused pose (graph_pose_stage.hpp)
  kAssociation,     // "association" (association_stage.hpp)
  kInertial,        // "inertial": IMU-driven error-state filter (inertial_stage.hpp)
  kInertialGraph,   // "inertial_graph": the inertial keyframe smoother (inertial_graph_stage.hpp)
  kOther,           // "other"
};
const char* stage_kind_name(StageKind kind);

}  // namespace sextant::engine
