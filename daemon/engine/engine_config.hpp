#pragma once
// Configuration of the engine's stages: plain structs with in-class defaults.  YAML parsing and validation with
// file:line errors live in daemon/config/; each stage's struct sits next to its stage.
#include "daemon/engine/association_stage_config.hpp"
#include "daemon/engine/dead_reckoning_stage_config.hpp"
#include "daemon/engine/filter_stage_config.hpp"
#include "daemon/engine/graph_stage_config.hpp"

#include <string>

namespace sextant::engine {

/// Which estimator's fused pose goes on FUSED_POSE (config key `engine.primary_estimator`); its spelling is the
/// estimator's name (Stage::estimator(), the suffix of FUSED_POSE_<ESTIMATOR>).
enum class PrimaryEstimator {
  kAuto,           // "auto": the most capable enabled stage, graph > filter > dead reckoning
  kDeadReckoning,  // "dead_reckoning"
  kEkf,            // "ekf"
  kPf,             // "pf"
  kGraph,          // "graph"
};
/// The kind of a config spelling; throws std::invalid_argument naming the spellings for any other name.
PrimaryEstimator primary_estimator_from_name(const std::string& name);
const char* primary_estimator_name(PrimaryEstimator estimator);

struct EngineConfig {
  /// The others are published on FUSED_POSE_<ESTIMATOR>.  An estimator whose stage does not run falls back to
  /// "auto".  The default is config/default.yaml's (the EKF).
  PrimaryEstimator primary_estimator = PrimaryEstimator::kEkf;
  DeadReckoningConfig dead_reckoning;
  FilterConfig filter;
  GraphConfig graph;
  AssociationConfig association;
};

}  // namespace sextant::engine
