// sextant listen [CHANNEL...]: prints every sextant message on the bus (or on the given channels), one line each.
#include "cli/command.hpp"
#include "cli/handle_until_stopped.hpp"
#include "cli/message_printer.hpp"
#include "daemon/runtime/raw_subscription.hpp"

#include <lcm/lcm-cpp.hpp>

#include <cstdio>

namespace {

struct Printer {
  int64_t remaining;  // stop after this many messages (< 0: never)
  void on_message(const lcm_recv_buf_t& rbuf, const std::string& channel) {
    if (remaining == 0) return;
    std::printf("%-16s %s\n", channel.c_str(), sextant::tools::describe_message(rbuf.data, rbuf.data_size).c_str());
    std::fflush(stdout);
    if (remaining > 0) --remaining;
  }
};

sextant::cli::RegisterCommand reg{
    "listen", [](CLI::App& app) {
      auto* cmd = app.add_subcommand("listen", "print decoded sextant messages live (all channels, or the ones named)");
      auto channels = std::make_shared<std::vector<std::string>>();
      auto url = std::make_shared<std::string>();
      auto count = std::make_shared<int64_t>(-1);
      auto seconds = std::make_shared<double>(0);
      cmd->add_option("channels", *channels, "channels (LCM regular expressions); default: all");
      cmd->add_option("--lcm-url", *url, "LCM URL");
      cmd->add_option("-n,--count", *count, "exit after this many messages");
      cmd->add_option("--seconds", *seconds, "exit after this many seconds");
      cmd->callback([=] {
        lcm::LCM lcm(*url);
        if (!lcm.good()) {
          std::fprintf(stderr,
                       "sextant listen: cannot start LCM on '%s' (is there a multicast route? "
                       "sudo ip route add 224.0.0.0/4 dev lo)\n",
                       url->c_str());
          throw CLI::RuntimeError(3);
        }
        Printer printer{*count};
        if (channels->empty()) sextant::runtime::subscribe_raw(lcm, ".*", &printer);
        for (const auto& c : *channels) sextant::runtime::subscribe_raw(lcm, c, &printer);
        sextant::cli::handle_until_stopped(lcm, *seconds, [&printer] { return printer.remaining == 0; });
      });
    }};
}  // namespace
