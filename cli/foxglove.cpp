// sextant foxglove [--port 8765] [--bind ADDR] [--lcm-url URL]: every message on the LCM bus, live, for Foxglove
// (and Lichtblick) over the Foxglove WebSocket protocol: a separate process on the bus, so the daemon stays as it is.
// Topics and schemas: viewer/topics.hpp; the server: viewer/foxglove_bridge.hpp.
#include "daemon/runtime/raw_subscription.hpp"
#include "daemon/runtime/udp_drops.hpp"
#include "cli/command.hpp"
#include "cli/handle_until_stopped.hpp"
#include "viewer/foxglove_bridge.hpp"

#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <cstdio>
#include <optional>
#include <string>

namespace {

using namespace sextant::viewer;

struct Feed {
  FoxgloveBridge* bridge;
  void on_message(const lcm_recv_buf_t& rbuf, const std::string& channel) {
    bridge->on_lcm(channel, static_cast<const uint8_t*>(rbuf.data), rbuf.data_size);
  }
};

/// `kernel_drops`: datagrams the kernel dropped at this process's sockets since the start (their receive buffers
/// overflowed: the bus's messages the bridge never saw), or nullopt where /proc does not say.
void print_stats(const FoxgloveBridgeStats& s, std::optional<int64_t> kernel_drops) {
  std::printf(
      "bridge: %lld LCM messages (%lld not sextant's, not shown; %lld dropped before mapping, %lld failed), "
      "%lld channels advertised, %lld clients connected since start (%lld refused); %s datagrams dropped by the "
      "kernel before the bridge read them\n",
      (long long)s.lcm_messages, (long long)s.without_json, (long long)s.input_dropped, (long long)s.mapping_failures,
      (long long)s.channels, (long long)s.clients_connected, (long long)s.rejected_connections,
      kernel_drops ? std::to_string(*kernel_drops).c_str() : "?");
  for (const auto& c : s.clients)
    std::printf("  client %s: %lld subscriptions, %lld sent, %lld dropped (queue now %zu, at most %zu)\n",
                c.address.c_str(), (long long)c.subscriptions, (long long)c.sent, (long long)c.dropped, c.queued,
                c.queued_max);
  std::fflush(stdout);
}

sextant::cli::RegisterCommand reg{
    "foxglove", [](CLI::App& app) {
      auto* cmd = app.add_subcommand("foxglove",
                                     "serve the LCM bus live to Foxglove / Lichtblick (Foxglove WebSocket "
                                     "protocol; open ws://ADDR:PORT in the viewer)");
      auto o = std::make_shared<FoxgloveBridgeOptions>();
      auto url = std::make_shared<std::string>();
      auto stats_seconds = std::make_shared<double>(0);
      auto lcm_queue = std::make_shared<int>(sextant::runtime::kDefaultLcmQueue);
      cmd->add_option("--port", o->port, "TCP port (0: any free one)");
      cmd->add_option("--bind", o->bind_address,
                      "address to listen on (default 127.0.0.1: this machine only; 0.0.0.0: every "
                      "interface)");
      cmd->add_option("--lcm-url", *url, "LCM URL");
      cmd->add_option("--queue", o->max_queued_messages, "messages queued per client before the oldest is dropped")
          ->check(CLI::Range(size_t{16}, size_t{1} << 24));
      cmd->add_option("--lcm-queue", *lcm_queue,
                      "LCM messages held for the bridge while it maps (LCM drops, uncounted, beyond)")
          ->check(CLI::Range(30, 1 << 20));
      cmd->add_option("--stats-seconds", *stats_seconds, "print the bridge's counters this often (0: at exit only)")
          ->check(CLI::NonNegativeNumber);
      cmd->callback([=] {
        lcm::LCM lcm(*url);
        if (!lcm.good()) {
          std::fprintf(stderr,
                       "sextant foxglove: cannot start LCM on '%s' (is there a multicast route? "
                       "sudo ip route add 224.0.0.0/4 dev lo)\n",
                       url->c_str());
          throw CLI::RuntimeError(3);
        }
        std::unique_ptr<FoxgloveBridge> bridge;
        try {
          bridge = std::make_unique<FoxgloveBridge>(*o);
        } catch (const std::exception& e) {
          std::fprintf(stderr, "sextant foxglove: %s\n", e.what());
          throw CLI::RuntimeError(2);
        }
        std::printf("sextant foxglove: serving on ws://%s:%u (Foxglove: Open connection -> Foxglove WebSocket)\n",
                    o->bind_address.c_str(), bridge->port());
        std::fflush(stdout);
        Feed feed{bridge.get()};
        sextant::runtime::subscribe_raw(lcm, ".*", &feed, *lcm_queue);
        const int64_t drops_at_start = sextant::runtime::udp_receive_drops().value_or(0);
        const auto kernel_drops = [&]() -> std::optional<int64_t> {
          const auto d = sextant::runtime::udp_receive_drops();
          return d ? std::optional<int64_t>(*d - drops_at_start) : std::nullopt;
        };
        auto last = std::chrono::steady_clock::now();
        sextant::cli::handle_until_stopped(lcm, 0, [&] {
          if (*stats_seconds > 0 &&
              std::chrono::steady_clock::now() - last > std::chrono::duration<double>(*stats_seconds)) {
            last = std::chrono::steady_clock::now();
            print_stats(bridge->stats(), kernel_drops());
          }
          return false;
        });
        print_stats(bridge->stats(), kernel_drops());
      });
    }};

}  // namespace
