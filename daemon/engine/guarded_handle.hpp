#pragma once
// Handling one event so that nothing a stage throws escapes: the daemon's stage threads and the replay run the same
// sequence, so that a replay continues past an event that made a stage fail exactly as the daemon does.
//   1. stage.handle(event): when it throws, the failure is returned (what threw and its message);
//   2. stage.recover(event): the stage restores a usable state (rebuild a factorization, reset a body) before the
//      next event; whether that worked is part of the returned failure.
#include "daemon/engine/stage.hpp"

#include <optional>
#include <string>

namespace sextant::engine {

/// Runs `f`; the message of what it threw, or nullopt when it returned.
template <class F>
std::optional<std::string> call_guarded(F&& f) noexcept {
  try {
    f();
    return std::nullopt;
  } catch (const std::exception& e) {
    return std::string(e.what());
  } catch (...) {
    return std::string("an exception that is not a std::exception");
  }
}

struct StageFailure {
  std::string message;          // "handle: <what handle threw>"
  bool recovered = false;       // Stage::recover returned normally
  std::string recover_message;  // what recover threw ("" when it recovered)
};

/// handle, and recover when handle threw (see the file comment).
inline std::optional<StageFailure> handle_guarded(Stage& stage, const Event& event, const Emit& emit) noexcept {
  auto thrown = call_guarded([&] { stage.handle(event, emit); });
  if (!thrown) return std::nullopt;
  StageFailure f;
  f.message = "handle: " + *thrown;
  auto recover_thrown = call_guarded([&] { stage.recover(event); });
  f.recovered = !recover_thrown;
  if (recover_thrown) f.recover_message = "recover: " + *recover_thrown;
  return f;
}

}  // namespace sextant::engine
