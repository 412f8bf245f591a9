#pragma once
// The state directory (README, "State directory"): sextantd saves every engine stage's state (Stage::save) to
// DIR/sextantd.state every `state_period_s` of wall-clock time and at shutdown, and a daemon started with the same
// directory and config restores its stages from it before it reads the bus, so that it continues where the saved one
// was: loops to keyframes from before a crash still close, the filters continue from their estimates.
// The file format and its checks are state_file.hpp's.  A file that fails them, or a section a stage refuses, is an
// error naming the file (sextantd exits with kExitState) unless the daemon was told to discard it
// (--discard-bad-state): the file is then renamed aside (sextantd.state.bad-<unix time>, never deleted) and the
// daemon starts fresh.
#include "daemon/engine/stage.hpp"
#include "daemon/runtime/state_file.hpp"

#include <memory>
#include <string>
#include <vector>

namespace sextant::runtime {

class StageRunner;

/// DIR/sextantd.state.
std::string state_file_path(const std::string& dir);

/// Restores `stages` (freshly constructed, not yet fed) from the state file at `path`: false when there is no file.
/// The file must hold one section per stage, named and ordered as `stages`.  Throws StateFileError naming the file
/// (and the stage whose section failed); the stages are then partly restored and must be built again.
bool restore_stages(const std::string& path, uint64_t fingerprint, const std::vector<engine::Stage*>& stages);

/// Renames a bad state file aside (PATH.bad-<unix time>); returns the new name.  Throws StateFileError.
std::string set_state_file_aside(const std::string& path);

struct StateSave {
  size_t bytes = 0;       // the file's size
  double collect_ms = 0;  // stages saving their state (each between two of its events)
  double write_ms = 0;    // encoding, writing, fsync, rename
};

/// Saves every runner's stage (StageRunner::with_stage) to `path`, atomically.  Throws StateFileError.
StateSave save_stages(const std::string& path, uint64_t fingerprint,
                      const std::vector<std::unique_ptr<StageRunner>>& runners);

}  // namespace sextant::runtime
