#pragma once
// Configuration of the engine's stages: plain structs with in-class defaults.  YAML parsing and validation with
// file:line errors live in daemon/config/; each stage's struct sits next to its stage.
#include "daemon/engine/association_stage_config.hpp"
#include "daemon/engine/dead_reckoning_stage_config.hpp"
#include "daemon/engine/filter_stage_config.hpp"
#include "daemon/engine/graph_stage_config.hpp"
#include "daemon/engine/inertial_stage_config.hpp"
#include "daemon/engine/stage_kinds.hpp"

#include <string>

namespace sextant::engine {

struct EngineConfig {
  /// Which estimator's fused pose goes on FUSED_POSE (stage_kinds.hpp); the others are published on
  /// FUSED_POSE_<ESTIMATOR>.  An estimator whose stage does not run falls back to
  /// "auto".  The default is config/default.yaml's (the EKF).
  PrimaryEstimator primary_estimator = PrimaryEstimator::kEkf;
  DeadReckoningConfig dead_reckoning;
  FilterConfig filter;
  GraphConfig graph;
  AssociationConfig association;
  InertialConfig inertial;
};

}  // namespace sextant::engine
