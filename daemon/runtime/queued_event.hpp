#pragma once
// An event on its way to a stage's thread, with the time the daemon received it (a stage's latency is measured from
// it to the end of the stage's `handle`).
#include "daemon/engine/events.hpp"

#include <chrono>

namespace sextant::runtime {

struct QueuedEvent {
  engine::Event event;
  std::chrono::steady_clock::time_point received;
};

}  // namespace sextant::runtime
