#pragma once
// The engine: every enabled stage, driven synchronously.  No LCM, no threads: replay calls `handle` in utime
// order; the daemon instead routes each event to the stages that accept it through per-stage queues and threads
// (daemon/runtime/stage_runner.hpp), calling the same Stage objects.  The one piece of state two stages share, the
// graph's map -> odometry correction board (graph_correction.hpp), is a plain map unless the caller gives another
// (the daemon's is guarded for its two threads).
#include "daemon/engine/engine_config.hpp"
#include "daemon/engine/graph_correction.hpp"
#include "daemon/engine/stage.hpp"

#include <memory>
#include <vector>

namespace sextant::engine {

class Engine {
 public:
  /// `corrections`: the board between the graph stage and the graph pose stage (nullptr: a GraphCorrections).
  explicit Engine(const EngineConfig& config, std::shared_ptr<GraphCorrectionBoard> corrections = nullptr);

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

/// The stages the config enables, in a fixed order (dead reckoning, filter, graph and graph pose around
/// `corrections` (nullptr: a GraphCorrections), association).
std::vector<std::unique_ptr<Stage>> make_stages(const EngineConfig& config,
                                                std::shared_ptr<GraphCorrectionBoard> corrections = nullptr);

}  // namespace sextant::engine
