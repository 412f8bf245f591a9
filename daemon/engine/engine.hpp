#pragma once
// The engine: every enabled stage, driven synchronously.  No LCM, no threads: replay calls `handle` in utime
// order; the daemon instead routes each event to the stages that accept it through per-stage queues and threads
// (daemon/runtime/stage_runner.hpp), calling the same Stage objects.
#include "daemon/engine/engine_config.hpp"
#include "daemon/engine/stage.hpp"

#include <memory>
#include <vector>

namespace sextant::engine {

class Engine {
 public:
  explicit Engine(const EngineConfig& config);

  /// Hands `event` to every stage that accepts it, in stage order.
  void handle(const Event& event, const Emit& emit);
  /// End of input: every stage flushes what is pending.
  void finish(const Emit& emit);

  const std::vector<std::unique_ptr<Stage>>& stages() const { return stages_; }
  std::vector<std::unique_ptr<Stage>>& stages() { return stages_; }
  const EngineConfig& config() const { return config_; }
  /// The estimator whose FusedPose goes on FUSED_POSE: the configured one, or with "auto" the most capable
  /// enabled stage (graph > ekf/pf > dead_reckoning).
  std::string primary_estimator() const;

 private:
  EngineConfig config_;
  std::vector<std::unique_ptr<Stage>> stages_;
};

/// The stages the config enables, in a fixed order (dead reckoning, filter, association).
std::vector<std::unique_ptr<Stage>> make_stages(const EngineConfig& config);

}  // namespace sextant::engine
