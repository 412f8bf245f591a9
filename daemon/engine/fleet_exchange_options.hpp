#pragma once
// The options of the fleet exchange (fleet_exchange.hpp), apart so that the graph stage's config does not pull in the
// exchange itself.
#include <string>
#include <vector>

namespace sextant::engine {

/// engine.graph.fleet.exchange (config/default.yaml documents each key).
struct FleetExchangeOptions {
  bool enabled = false;
  std::string self;                  // this daemon's name: daemon.name, set by the config reader when enabled
  std::vector<std::string> members;  // the fleet's daemon names (daemon.name of each), this daemon's included
  int retain = 20000;                // contributions kept per local body for repair
  int retain_mb = 64;                // ... and at most this many MB of them (wire size)
  double heartbeat_period_s = 1.0;
  double repair_backoff_s = 0.2;      // a gap is asked for this long after it is seen, then again after twice as long
  double repair_backoff_max_s = 5.0;  // ... up to this
  int max_streams_per_sender = 64;    // bodies one member may contribute
  int reorder_window = 4096;          // contributions of a stream held ahead of the next one expected
  int reorder_mb = 16;                // ... and at most this many MB of them per stream
  int max_repair_range = 1024;        // contributions asked for in one request per stream
  double repair_bytes_per_s = 1.0e6;  // resent per requester at most
  int max_message_bytes = 60000;      // a FLEET message's encoded size at most (under one 64 KB datagram)
  double restart_wait_s = 2.0;        // a restarted owner waits this long after the last of its tail it took back
};

}  // namespace sextant::engine
