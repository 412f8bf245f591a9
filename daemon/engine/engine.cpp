#include "daemon/engine/engine.hpp"

#include "daemon/engine/association_stage.hpp"
#include "daemon/engine/dead_reckoning_stage.hpp"
#include "daemon/engine/filter_stage.hpp"
#include "daemon/engine/graph_pose_stage.hpp"
#include "daemon/engine/graph_stage.hpp"
#include "daemon/engine/inertial_graph_stage.hpp"
#include "daemon/engine/inertial_stage.hpp"
#include "daemon/engine/particle_filter_stage.hpp"

namespace sextant::engine {

std::vector<std::unique_ptr<Stage>> make_stages(const EngineConfig& config,
                                                std::shared_ptr<GraphCorrectionBoard> corrections) {
  std::vector<std::unique_ptr<Stage>> stages;
  if (config.dead_reckoning.enabled) stages.push_back(std::make_unique<DeadReckoningStage>(config.dead_reckoning));
  if (config.filter.type == FilterType::kEkf) stages.push_back(std::make_unique<FilterStage>(config.filter));
  if (config.filter.type == FilterType::kPf) stages.push_back(std::make_unique<ParticleFilterStage>(config.filter));
  if (config.graph.enabled) {
    // Two stages around one shared correction: the back end (keyframes, loops, solves) and the fused-pose path that
    // must never wait for a solve (graph_correction.hpp).
    if (!corrections) corrections = std::make_shared<GraphCorrections>();
    stages.push_back(std::make_unique<GraphStage>(config.graph, corrections));
    stages.push_back(std::make_unique<GraphPoseStage>(corrections));
  }
  if (config.association.enabled) stages.push_back(std::make_unique<AssociationStage>(config.association));
  if (config.inertial.enabled) stages.push_back(std::make_unique<InertialStage>(config.inertial));
  if (config.inertial.enabled && config.inertial.graph.enabled)
    stages.push_back(std::make_unique<InertialGraphStage>(config.inertial));
  return stages;
}

Engine::Engine(const EngineConfig& config, std::shared_ptr<GraphCorrectionBoard> corrections)
    : config_(config), stages_(make_stages(config, std::move(corrections))) {}

namespace {

// How capable an estimator is, for "auto": graph > inertial filter > inertial smoother > filter > dead reckoning
// (the inertial smoother publishes beside the inertial filter, which stays FUSED_POSE unless chosen).
int capability(PrimaryEstimator estimator) {
  switch (estimator) {
    case PrimaryEstimator::kGraph:
      return 5;
    case PrimaryEstimator::kInertial:
      return 4;
    case PrimaryEstimator::kInertialGraph:
      return 3;
    case PrimaryEstimator::kEkf:
    case PrimaryEstimator::kPf:
      return 2;
    case PrimaryEstimator::kDeadReckoning:
      return 1;
    case PrimaryEstimator::kAuto:
      break;
  }
  return -1;
}

}  // namespace

std::string Engine::primary_estimator() const {
  if (config_.primary_estimator != PrimaryEstimator::kAuto) {
    for (const auto& stage : stages_)
      if (stage->estimator_kind() == config_.primary_estimator) return std::string(stage->estimator());
  }
  std::string best;
  int best_rank = -1;
  for (const auto& stage : stages_) {
    const auto e = stage->estimator_kind();
    const int rank = e ? capability(*e) : -1;
    if (rank > best_rank) best_rank = rank, best = std::string(stage->estimator());
  }
  return best;
}

void Engine::handle(const Event& event, const Emit& emit) {
  for (auto& stage : stages_)
    if (stage->accepts(event)) stage->handle(event, emit);
}

void Engine::finish(const Emit& emit) {
  for (auto& stage : stages_) stage->finish(emit);
}

}  // namespace sextant::engine
