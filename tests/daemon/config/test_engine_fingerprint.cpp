// The state directory's config fingerprint is of the parsed engine config, not its text: a config that writes a
// default out and one that leaves it out accept each other's state; a changed value does not.
#include "daemon/config/daemon_config.hpp"

#include <doctest/doctest.h>

#include <fstream>
#include <sstream>

using namespace sextant;

TEST_CASE("config: the engine fingerprint depends on the parsed values, not on which defaults are written") {
  const uint64_t nothing_written = config::parse_daemon_config("", "empty.yaml").engine_fingerprint;
  const uint64_t defaults_written = config::parse_daemon_config(
                                        "engine:\n  primary_estimator: ekf\n  association:\n    max_pending_scans: 16\n"
                                        "  graph:\n    loops:\n      n1: 3   # the default\n      robust: dcs\n",
                                        "defaults.yaml")
                                        .engine_fingerprint;
  CHECK(defaults_written == nothing_written);  // the text's hash told these apart
  // The whole reference file writes every default.
  std::ifstream in(std::string(SEXTANT_SOURCE_DIR) + "/config/default.yaml");
  std::stringstream text;
  text << in.rdbuf();
  CHECK(config::parse_daemon_config(text.str(), "default.yaml").engine_fingerprint == nothing_written);
  // Only the engine counts: channels and daemon keys do not.
  CHECK(
      config::parse_daemon_config("daemon:\n  queue_capacity: 7\nchannels:\n  prefix: R1_\n", "t").engine_fingerprint ==
      nothing_written);
  // A changed value changes it, wherever it is (a number, a nested one, an enum, a flag, a list).
  for (const char* changed :
       {"engine:\n  graph:\n    loops:\n      n1: 4\n", "engine:\n  association:\n    max_pending_scans: 17\n",
        "engine:\n  primary_estimator: graph\n", "engine:\n  graph:\n    loops:\n      propose: false\n",
        "engine:\n  association:\n    region_min: [0, 0, 0]\n    region_max: [1, 1, 1]\n",
        "engine:\n  graph:\n    smoother:\n      wildfire: 0.5\n"}) {
    INFO(changed);
    CHECK(config::parse_daemon_config(changed, "changed.yaml").engine_fingerprint != nothing_written);
  }
  // A value written as another spelling of the same number is the same value.
  CHECK(config::parse_daemon_config("engine:\n  association:\n    alpha: 0.50\n", "t").engine_fingerprint ==
        config::parse_daemon_config("engine:\n  association:\n    alpha: 5.0e-1\n", "t").engine_fingerprint);
}
