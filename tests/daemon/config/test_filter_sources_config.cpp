// The filter's per-source odometry settings in YAML: parsed into FilterConfig, bad settings refused with the place.
#include "daemon/config/daemon_config.hpp"

#include "config_error_of.hpp"

#include <doctest/doctest.h>

#include <string>

using sextant::config::ConfigError;
using sextant::config::parse_daemon_config;

namespace {
const auto error_of = sextant::test::config_error_of;
}  // namespace

TEST_CASE("filter sources: mapping to bodies, masks, modes, gates, timeouts") {
  const auto c = parse_daemon_config(R"(
engine:
  filter:
    history_s: 1.5
    sources:
      wheel: {body: robot1, predict: true}
      vo: {body: robot1, fuse: [x, yaw], differential: true, gate: 11.34, timeout_s: 0.5}
      gyro: {body: robot1, fuse: [vyaw]}
)",
                                     "t.yaml");
  const auto& f = c.engine.filter;
  CHECK(f.history_s == doctest::Approx(1.5));
  REQUIRE(f.sources.size() == 3);
  CHECK(f.sources.at("wheel").predict);
  CHECK(f.sources.at("vo").body == "robot1");
  CHECK(f.sources.at("vo").fuse == std::array<bool, 6>{true, false, true, false, false, false});
  CHECK(f.sources.at("vo").gate == doctest::Approx(11.34));
  CHECK(f.sources.at("vo").timeout_s == doctest::Approx(0.5));
  CHECK(f.sources.at("gyro").fuse == std::array<bool, 6>{false, false, false, false, false, true});
  // A body named like an unlisted source gets it as its predictor.
  CHECK(error_of("engine:\n  filter:\n    sources:\n      vo: {body: robot1}\n").empty());
}

TEST_CASE("filter sources: errors name the place") {
  CHECK(error_of("engine:\n  filter:\n    sources:\n      vo: {body: r, fuse: [x, z]}\n").find("test.yaml:4") !=
        std::string::npos);
  CHECK(
      error_of("engine:\n  filter:\n    sources:\n      vo: {body: r, fuse: [x, z]}\n").find("unknown component 'z'") !=
      std::string::npos);
  // Two predictors, none, a differential pose with velocities, a masked predictor, unknown key, negative gate.
  CHECK(error_of(
            "engine:\n  filter:\n    sources:\n      a: {body: r, predict: true}\n      b: {body: r, predict: true}\n")
            .find("exactly one") != std::string::npos);
  CHECK(error_of("engine:\n  filter:\n    sources:\n      a: {body: r}\n      r: {body: r}\n").find("exactly one") !=
        std::string::npos);
  CHECK(error_of("engine:\n  filter:\n    sources:\n      a: {body: r, fuse: [x, vx]}\n").find("twice") !=
        std::string::npos);
  CHECK(error_of("engine:\n  filter:\n    sources:\n      r: {predict: true, fuse: [x, y]}\n").find("predicts") !=
        std::string::npos);
  CHECK(error_of("engine:\n  filter:\n    sources:\n      a: {body: r, gait: 3}\n").find("gait") != std::string::npos);
  CHECK(error_of("engine:\n  filter:\n    sources:\n      a: {body: r, gate: -1}\n").find("test.yaml:4") !=
        std::string::npos);
  CHECK(!error_of("engine:\n  filter:\n    sources: [a, b]\n").empty());
}
