#pragma once
// An event on its way to a stage's thread, with the time the daemon received it (a stage's latency is measured from
// it to the end of the stage's `handle`).
#include "daemon/engine/events.hpp"

#include <chrono>
#include <string>
#include <utility>

namespace sextant::runtime {

struct QueuedEvent {
  QueuedEvent() = default;
  QueuedEvent(engine::Event e, std::chrono::steady_clock::time_point r, std::string forget = {})
      : event(std::move(e)), received(r), forget_first(std::move(forget)) {}

  engine::Event event;
  std::chrono::steady_clock::time_point received;
  /// A body (odometry source) the stage forgets just before this event: its clock was re-synchronised and this is
  /// its first message on the new clock (Intake::resynced_body).  Empty for every other event.
  std::string forget_first;
};

}  // namespace sextant::runtime
