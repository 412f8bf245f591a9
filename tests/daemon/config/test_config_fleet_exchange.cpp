// engine.graph.fleet.exchange and the fleet's channels: defaults as config/default.yaml documents them, every key read,
// daemon.name taken as the exchange's own name, and each wrong value refused at its file:line.
#include "config_error_of.hpp"
#include "daemon/config/daemon_config.hpp"

#include <doctest/doctest.h>

#include <string>

using sextant::config::parse_daemon_config;
using sextant::test::config_error_of;

namespace {

std::string exchange(const std::string& keys, const std::string& name = "alpha") {
  return "daemon:\n  name: " + name +
         "\n"
         "engine:\n"
         "  graph:\n"
         "    fleet:\n"
         "      exchange:\n" +
         keys;
}

}  // namespace

TEST_CASE("config: fleet exchange off by default, on with its members and every key read") {
  const auto d = parse_daemon_config("", "t.yaml");
  CHECK_FALSE(d.engine.graph.fleet_exchange.enabled);
  CHECK(d.engine.graph.fleet_exchange.self.empty());
  CHECK(d.engine.graph.lifelong.hold_frame);  // one daemon: a thinning holds the frame where it was
  CHECK(d.channels.fleet == "FLEET");
  CHECK(d.channels.fleet_control == "FLEET_CONTROL");
  const auto c = parse_daemon_config(exchange("        enabled: true\n"
                                              "        members: [alpha, beta]\n"
                                              "        retain: 500\n"
                                              "        retain_mb: 8\n"
                                              "        heartbeat_period_s: 0.5\n"
                                              "        repair_backoff_s: 0.1\n"
                                              "        repair_backoff_max_s: 2\n"
                                              "        max_streams_per_sender: 3\n"
                                              "        reorder_window: 100\n"
                                              "        reorder_mb: 2\n"
                                              "        max_repair_range: 50\n"
                                              "        repair_bytes_per_s: 20000\n"
                                              "        max_message_bytes: 40000\n"
                                              "        restart_wait_s: 0.5\n") +
                                         "channels:\n  prefix: ROBOT1_\n  fleet: TEAM\n",
                                     "t.yaml");
  const auto& x = c.engine.graph.fleet_exchange;
  CHECK(x.enabled);
  CHECK_FALSE(c.engine.graph.lifelong.hold_frame);  // every daemon's frame on the same first keyframe
  CHECK(x.self == "alpha");
  CHECK(x.members == std::vector<std::string>{"alpha", "beta"});
  CHECK(x.retain == 500);
  CHECK(x.retain_mb == 8);
  CHECK(x.heartbeat_period_s == 0.5);
  CHECK(x.repair_backoff_s == 0.1);
  CHECK(x.repair_backoff_max_s == 2);
  CHECK(x.max_streams_per_sender == 3);
  CHECK(x.reorder_window == 100);
  CHECK(x.reorder_mb == 2);
  CHECK(x.max_repair_range == 50);
  CHECK(x.repair_bytes_per_s == 20000);
  CHECK(x.max_message_bytes == 40000);
  CHECK(x.restart_wait_s == 0.5);
  CHECK(c.channels.fleet == "TEAM");  // the prefix is not the fleet's
  CHECK(c.channels.full(c.channels.odometry) == "ROBOT1_ODOMETRY");
}

TEST_CASE("config: a wrong fleet exchange is refused at its file:line") {
  // daemon.name must be a member (the line of `members`).
  CHECK(
      config_error_of(exchange("        enabled: true\n        members: [beta, gamma]\n")).starts_with("test.yaml:8:"));
  CHECK(config_error_of(exchange("        enabled: true\n        members: [beta, gamma]\n"))
            .find("daemon.name 'alpha' is not among the members") != std::string::npos);
  CHECK(config_error_of(exchange("        enabled: true\n")).starts_with("test.yaml:7:"));  // no members
  CHECK(config_error_of(exchange("        members: [alpha, alpha]\n")).find("listed twice") != std::string::npos);
  CHECK(config_error_of(exchange("        members: [\"\"]\n")).starts_with("test.yaml:7:"));
  CHECK(config_error_of(exchange("        retain: 0\n")).starts_with("test.yaml:7:"));
  CHECK(config_error_of(exchange("        max_message_bytes: 70000\n")).starts_with("test.yaml:7:"));
  CHECK(config_error_of(exchange("        restart_wait_s: 0\n")).starts_with("test.yaml:7:"));
  CHECK(config_error_of(exchange("        repair_backoff_s: 2\n        repair_backoff_max_s: 1\n"))
            .find("repair_backoff_max_s") != std::string::npos);
  CHECK(config_error_of(exchange("        retian: 5\n")).starts_with("test.yaml:7:"));  // unknown key
  CHECK(config_error_of("daemon:\n  name: alpha\nengine:\n  graph:\n    fleet:\n      enabled: false\n      exchange:\n"
                        "        enabled: true\n        members: [alpha]\n")
            .find("fleet.enabled' is false") != std::string::npos);
  // The fleet's channels: not one of the daemon's own, not each other.
  CHECK(config_error_of("channels:\n  fleet: ODOMETRY\n").starts_with("test.yaml:2:"));
  CHECK(config_error_of("channels:\n  prefix: R_\n  fleet: R_TRAJECTORY\n").starts_with("test.yaml:3:"));
  CHECK(config_error_of("channels:\n  fleet_control: FLEET\n").starts_with("test.yaml:2:"));
  CHECK(config_error_of("channels:\n  fleet: \"A B\"\n").starts_with("test.yaml:2:"));
}
