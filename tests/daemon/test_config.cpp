// Config parsing: defaults, overrides, and every error naming its file:line.
#include "assoc/chi_square.hpp"
#include "daemon/config/daemon_config.hpp"
#include "daemon/engine/graph_stage_config.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <string>

using sextant::config::ConfigError;
using sextant::config::parse_daemon_config;

namespace {
// The message of the ConfigError thrown by parsing `yaml`, or "" when it parses.
std::string error_of(const std::string& yaml) {
  try {
    parse_daemon_config(yaml, "test.yaml");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST_CASE("the shipped configs parse: default enables dead reckoning, mrclam fits the data set") {
  CHECK(sextant::config::load_daemon_config(std::string(SEXTANT_SOURCE_DIR) + "/config/mrclam.yaml").queue_capacity == 4096);
  const auto c = sextant::config::load_daemon_config(std::string(SEXTANT_SOURCE_DIR) + "/config/default.yaml");
  CHECK(c.name == "sextantd");
  CHECK(c.channels.odometry == "ODOMETRY");
  CHECK(c.channels.status == "SEXTANT_STATUS");
  CHECK(c.engine.dead_reckoning.enabled);
  CHECK(c.queue_capacity == 1024);
}

TEST_CASE("an empty file gives every default") {
  const auto c = parse_daemon_config("", "empty.yaml");
  CHECK(c.status_period_s == doctest::Approx(1.0));
  CHECK(c.channels.fused_pose == "FUSED_POSE");
  CHECK(c.channels.full("FUSED_POSE") == "FUSED_POSE");
}

TEST_CASE("values override defaults and the prefix applies to every channel") {
  const auto c = parse_daemon_config("daemon:\n  queue_capacity: 7\nchannels:\n  prefix: ROBOT1_\n  odometry: WHEEL\n", "t");
  CHECK(c.queue_capacity == 7);
  CHECK(c.channels.full(c.channels.odometry) == "ROBOT1_WHEEL");
}

TEST_CASE("an unknown key names its line and column") {
  const std::string e = error_of("daemon:\n  name: x\n  queue_capacty: 5\n");
  CHECK(e.find("test.yaml:3:3:") == 0);
  CHECK(e.find("unknown key 'daemon.queue_capacty'") != std::string::npos);
  CHECK(e.find("queue_capacity") != std::string::npos);  // lists the known keys
}

TEST_CASE("an unknown top-level section is an error") {
  CHECK(error_of("deamon:\n  name: x\n").find("test.yaml:1:1: unknown key 'deamon'") == 0);
}

TEST_CASE("a value of the wrong type names its line") {
  const std::string e = error_of("daemon:\n  status_period_s: often\n");
  CHECK(e.find("test.yaml:2:20:") == 0);
  CHECK(e.find("expected a number") != std::string::npos);
}

TEST_CASE("a value out of range names its line and the bound") {
  const std::string e = error_of("\n\ndaemon:\n  queue_capacity: 0\n");
  CHECK(e.find("test.yaml:4:19:") == 0);
  CHECK(e.find("must be in [1,") != std::string::npos);
}

TEST_CASE("enumerations list the allowed values") {
  const std::string e = error_of("engine:\n  primary_estimator: kalman\n");
  CHECK(e.find("test.yaml:2:22:") == 0);
  CHECK(e.find("auto, dead_reckoning, ekf, pf, graph") != std::string::npos);
}

TEST_CASE("a bad channel name is refused") {
  CHECK(error_of("channels:\n  odometry: \"ODO METRY\"\n").find("test.yaml:2:13:") == 0);
}

TEST_CASE("YAML syntax errors name the line") {
  const std::string e = error_of("daemon:\n  name: [unclosed\n");
  CHECK(e.find("test.yaml:") == 0);
  CHECK(e.find("YAML syntax error") != std::string::npos);
}

TEST_CASE("a section that is not a mapping is refused") {
  CHECK(error_of("daemon: 5\n").find("test.yaml:1:9: 'daemon': expected a mapping") == 0);
}

TEST_CASE("a missing file is a config error naming the path") {
  CHECK_THROWS_WITH_AS(sextant::config::load_daemon_config("/nonexistent/x.yaml"),
                       "/nonexistent/x.yaml: cannot open config file", ConfigError);
}

TEST_CASE("the loops' kernel width: auto by default (a chi-square quantile of the loop's dimension), or a number") {
  using sextant::engine::kernel_width_for;
  // Defaults: DCS, gate probability 0.999.  The width is the loop gate's quantile (assoc::chi2_quantile, the
  // Wilson-Hilferty approximation), which is within 2 % of the tables: 3 dof 16.266, 6 dof 22.458.
  const auto d = parse_daemon_config("", "t").engine.graph;
  CHECK_FALSE(d.kernel_width.has_value());
  CHECK(kernel_width_for(d, true) == sextant::assoc::chi2_quantile(3, 0.999));
  CHECK(kernel_width_for(d, false) == sextant::assoc::chi2_quantile(6, 0.999));
  CHECK(kernel_width_for(d, true) == doctest::Approx(16.266).epsilon(0.02));
  CHECK(kernel_width_for(d, false) == doctest::Approx(22.458).epsilon(0.02));
  // The shipped default config says auto too.
  const auto shipped = sextant::config::load_daemon_config(std::string(SEXTANT_SOURCE_DIR) + "/config/default.yaml");
  CHECK_FALSE(shipped.engine.graph.kernel_width.has_value());
  // Huber's and Cauchy's delta act on sqrt(chi2): the square root of the same quantile; at 0.99, 6 dof: 16.812.
  const auto huber = parse_daemon_config("engine:\n  graph:\n    loops: {robust: huber, gate_probability: 0.99}\n", "t").engine.graph;
  CHECK(kernel_width_for(huber, false) == doctest::Approx(std::sqrt(sextant::assoc::chi2_quantile(6, 0.99))));
  CHECK(kernel_width_for(huber, false) == doctest::Approx(std::sqrt(16.812)).epsilon(0.01));
  // A number applies to both kinds of body; "auto" spelled out is the default.
  const auto five = parse_daemon_config("engine:\n  graph:\n    loops: {kernel_width: 5}\n", "t").engine.graph;
  CHECK(kernel_width_for(five, true) == 5.0);
  CHECK(kernel_width_for(five, false) == 5.0);
  CHECK_FALSE(parse_daemon_config("engine:\n  graph:\n    loops: {kernel_width: auto}\n", "t").engine.graph.kernel_width);
  // Anything else names its place.
  for (const char* bad : {"wide", "-1", "0", "1e400", "5m"}) {
    const std::string e = error_of(std::string("engine:\n  graph:\n    loops:\n      kernel_width: ") + bad + "\n");
    CHECK(e.find("test.yaml:4:21:") == 0);
    CHECK(e.find("expected 'auto' or a positive number") != std::string::npos);
  }
}
