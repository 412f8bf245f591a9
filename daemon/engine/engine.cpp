#include "daemon/engine/engine.hpp"

#include "daemon/engine/dead_reckoning_stage.hpp"

namespace sextant::engine {

std::vector<std::unique_ptr<Stage>> make_stages(const EngineConfig& config) {
  std::vector<std::unique_ptr<Stage>> stages;
  if (config.dead_reckoning.enabled) stages.push_back(std::make_unique<DeadReckoningStage>(config.dead_reckoning));
  return stages;
}

Engine::Engine(const EngineConfig& config) : config_(config), stages_(make_stages(config)) {}

void Engine::handle(const Event& event, const Emit& emit) {
  for (auto& stage : stages_)
    if (stage->accepts(event)) stage->handle(event, emit);
}

void Engine::finish(const Emit& emit) {
  for (auto& stage : stages_) stage->finish(emit);
}

}  // namespace sextant::engine
