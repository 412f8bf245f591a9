#pragma once
// A Foxglove WebSocket server (protocol foxglove.websocket.v1, https://github.com/foxglove/ws-protocol) for the LCM
// messages fed to it: `sextant foxglove` feeds it every message on the bus.  Each message goes through the viewer
// mapping (topics.hpp); each topic is advertised to every client as a channel (JSON encoding, JSON Schema) the first
// time it appears, and a client receives the messages of the channels it subscribes to, stamped with the time the
// bridge received them (ns since the Unix epoch).
//
// Slow viewers never slow the bus side: on_lcm() only queues a copy of the message (bounded); a mapping thread maps
// what has arrived, serializing each viewer message once, and hands each subscribed client the batch's shared
// payloads under that client's lock, once per batch; one I/O thread writes to the sockets, each client's queued
// messages framed together into one write (batched_write_stream.hpp).  Each client's queue is bounded (messages
// and bytes); when it is full the oldest message is dropped and counted (advertisements are never dropped).  The
// server listens on 127.0.0.1 by default and offers no capability by which a client changes anything (no parameters,
// services or client publishing): a client can only subscribe and unsubscribe.
#include "viewer/topics.hpp"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace sextant::viewer {

struct FoxgloveBridgeOptions {
  std::string bind_address = "127.0.0.1";
  uint16_t port = 8765;                  // 0: any free port (port() tells which)
  size_t max_queued_messages = 4096;     // per client
  size_t max_queued_bytes = 64u << 20;   // per client, and for the messages received but not yet mapped
  size_t max_input_messages = 1u << 16;  // received but not yet mapped (a burst); beyond, the oldest are dropped
  std::string name = "sextant";          // the server name clients show
};

struct FoxgloveClientStats {
  std::string address;  // "127.0.0.1:51234"
  int64_t subscriptions = 0;
  int64_t sent = 0;     // messages written to the socket
  int64_t dropped = 0;  // messages dropped from a full queue
  size_t queued = 0, queued_max = 0;
};

struct FoxgloveBridgeStats {
  int64_t lcm_messages = 0;       // fed to on_lcm and mapped
  int64_t input_dropped = 0;      // received faster than they could be mapped, past max_input_messages: dropped
  int64_t mapping_failures = 0;   // messages whose mapping threw (lost)
  int64_t without_json = 0;       // not a sextant message (nothing to show): dropped
  int64_t channels = 0;           // advertised
  int64_t clients_connected = 0;  // since start
  int64_t rejected_connections = 0;
  std::vector<FoxgloveClientStats> clients;  // connected now
};

class FoxgloveBridge {
 public:
  /// Binds and listens (throws std::runtime_error naming the address and port when it cannot), then serves on its
  /// own I/O thread until destroyed.
  explicit FoxgloveBridge(FoxgloveBridgeOptions options = {}, TopicMapperOptions mapping = {});
  ~FoxgloveBridge();
  FoxgloveBridge(const FoxgloveBridge&) = delete;
  FoxgloveBridge& operator=(const FoxgloveBridge&) = delete;

  uint16_t port() const;
  /// One LCM message from the bus, stamped with the time of this call.  Call from one thread (the LCM loop); it
  /// only copies the message into a bounded queue.
  void on_lcm(const std::string& channel, const uint8_t* data, size_t size);
  FoxgloveBridgeStats stats() const;

  struct Impl;  // the server's state (foxglove_bridge.cpp), shared with its client sessions

 private:
  std::shared_ptr<Impl> impl_;
};

}  // namespace sextant::viewer
