#pragma once
// What a fleet of daemons exchanges (one daemon per robot, each fed only its own robots' sensors; docs/graph.md "A
// fleet of daemons"), as engine values: both an input event (from FLEET and FLEET_CONTROL) and an output (to them).
// The codec turns them into fleet_contribution_t and fleet_control_t (lcmtypes/sextant/, which document every field)
// and back; daemon/engine/fleet_exchange.hpp numbers, repairs and orders them.
#include "estimators/slam/graph_contribution.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace sextant::engine {

/// A run of one body's contribution stream (fleet_contribution_t): the contributions numbered first, first + 1, ...
/// in the order the body's owner made them.
struct FleetContributions {
  int64_t utime = 0;   // when it was sent (the sender's clock)
  std::string sender;  // the daemon that owns `body` (daemon.name), or a member relaying from its copy (repair);
                       // the publisher stamps its own name on outputs
  std::string body;
  bool repair = false;  // resent on a repair request
  int64_t first = 1;    // the stream number of contributions[0], >= 1
  std::vector<slam::GraphContribution::What> contributions;
};

/// A range of one body's stream (fleet_range_t).
struct FleetRange {
  std::string body;
  int64_t first = 0, last = 0;  // heartbeat: retained [first, last] (0, 0: none yet); repair: asked [first, last]
};

/// A heartbeat or a repair request (fleet_control_t).
struct FleetControl {
  enum class Kind { kHeartbeat = 1, kRepair = 2 };
  int64_t utime = 0;
  std::string sender;  // the daemon that sends it
  Kind kind = Kind::kHeartbeat;
  std::string daemon;  // kRepair: the daemon asked to resend (the owner of the streams); kHeartbeat: empty
  std::vector<FleetRange> streams;
};

}  // namespace sextant::engine
