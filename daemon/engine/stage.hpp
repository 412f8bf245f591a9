#pragma once
// A stage of the engine: consumes the events it accepts, emits outputs.  A stage owns its estimator state and is
// driven from one thread at a time; it knows no threads (the daemon gives each stage its own thread and bounded queue,
// daemon/runtime/stage_runner.hpp; replay calls stages synchronously in utime order).  A stage must not throw for bad data: it counts and drops it.
#include "daemon/engine/outputs.hpp"
#include "daemon/engine/stage_kinds.hpp"
#include "estimators/archive/binary_archive.hpp"

#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace sextant::engine {

using Emit = std::function<void(Output)>;

/// Named counters a stage reports on the status channel (e.g. {"keyframes_rejected", 3}).
using Counters = std::vector<std::pair<std::string, int64_t>>;

class Stage {
 public:
  virtual ~Stage() = default;
  /// Which of the engine's stages this is: what code outside the stage asks instead of comparing names.
  virtual StageKind kind() const = 0;
  /// The name on the status channel and in reports: the kind's spelling (a stage of kind kOther names itself).
  virtual std::string_view name() const { return stage_kind_name(kind()); }
  /// Whether `handle` wants this event (the dispatcher routes only accepted events to the stage's queue).
  virtual bool accepts(const Event& event) const = 0;
  virtual void handle(const Event& event, const Emit& emit) = 0;
  /// After `handle(event)` threw (a solver failure, an allocation): bring the stage back to a consistent state
  /// before the next event, e.g. forget the body the event belongs to (it restarts from its next message) or
  /// rebuild a factorization from the graph.  The runtime counts the failure; the default keeps the state as is.
  virtual void recover(const Event& /*failed*/) {}
  /// The body `source` (an odometry source) went silent and the daemon forgot it (daemon.source_idle_s): free every
  /// per-body structure; if it speaks again it starts as a new body.  The default keeps nothing per body.
  virtual void forget(const std::string& /*source*/) {}
  /// Asks a long computation in progress to end early; called from another thread than the stage's (the daemon's
  /// shutdown, at its drain deadline: daemon/runtime/stage_runner.hpp), for good: the computation ends after the step
  /// under way, leaving the state consistent (what `save` writes stays valid), and later ones end early too.  The
  /// default does nothing: a stage whose work per event is bounded otherwise (budgets) needs none.
  virtual void interrupt() {}
  /// End of input (replay end, daemon shutdown): emit what is still pending.
  virtual void finish(const Emit& /*emit*/) {}
  virtual Counters counters() const { return {}; }
  /// The state directory (README, "State directory"): everything the stage needs to continue after a restart as if
  /// it had not stopped (estimates, per-body bookkeeping, counters), written between two events.  A stage may first
  /// bring its state to a canonical form (the graph stage refactorizes its smoothers), so that `load` into a fresh
  /// stage of the same config continues with the same outputs as this one.  The default keeps nothing: the stage
  /// restarts empty.
  virtual void save(archive::ArchiveWriter& /*w*/) {}
  /// Restores what `save` wrote, into a stage just constructed with the same config and not yet fed; throws
  /// archive::ArchiveError for anything that does not fit (the caller names the file).
  virtual void load(archive::ArchiveReader& /*r*/) {}
  /// The estimator of the FusedPose outputs this stage emits, none when it emits none.
  virtual std::optional<PrimaryEstimator> estimator_kind() const { return std::nullopt; }
  /// Its name ("dead_reckoning", "ekf", "pf", "graph": FusedPose::estimator), empty when the stage emits none.
  std::string_view estimator() const {
    const auto kind = estimator_kind();
    return kind ? primary_estimator_name(*kind) : std::string_view();
  }
};

}  // namespace sextant::engine
