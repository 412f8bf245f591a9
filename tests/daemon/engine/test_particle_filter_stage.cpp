// The particle filter stage (filter type "pf") on simulated logs: one FusedPose "pf" per odometry message, an error
// far below dead reckoning, the same output for the same seed, and the config keys with file:line errors.
#include "daemon/config/daemon_config.hpp"
#include "daemon/runtime/lcm_log.hpp"
#include "replay/replay_driver.hpp"
#include "sim/simulator.hpp"
#include "eval/trajectory_eval.hpp"

#include <doctest/doctest.h>

#include <cstdio>
#include <filesystem>

using namespace sextant;

namespace {

std::string simulated_log(const std::string& name, uint64_t seed, bool unknown_ids) {
  const auto log = (std::filesystem::temp_directory_path() / (name + std::to_string(::getpid()) + ".lcm")).string();
  tools::SimulationOptions o;
  o.duration_s = 60;
  o.seed = seed;
  o.unknown_ids = unknown_ids;
  runtime::LogWriter w(log);
  tools::simulate(o, w);
  return log;
}

double ate(const tools::ReplayResult& r, const std::string& estimator) {
  std::vector<tools::StampedPose> truth, e;
  for (const auto& t : r.truth_poses) truth.push_back({t.utime * 1e-6, t.pose});
  for (const auto& p : r.fused_poses.at(estimator)) e.push_back({p.utime * 1e-6, p.pose});
  return tools::absolute_trajectory_error(truth, e).error.rmse;
}

}  // namespace

TEST_CASE("particle filter stage: FastSLAM 2.0 poses at the odometry rate, far below dead reckoning, deterministic") {
  const auto log = simulated_log("sextant_pf_", 4, false);
  config::DaemonConfig cfg;
  cfg.engine.filter.type = engine::FilterType::kPf;
  cfg.engine.filter.pf.particles = 30;
  cfg.engine.filter.pf.seed = 5;
  const auto r = tools::replay_log(log, cfg);
  const auto& pf = r.fused_poses.at("pf");
  CHECK(pf.size() == r.fused_poses.at("dead_reckoning").size());
  const double a_pf = ate(r, "pf"), a_dr = ate(r, "dead_reckoning");
  MESSAGE("ATE pf " << a_pf << " m, dead reckoning " << a_dr << " m");
  CHECK(a_pf < 0.5 * a_dr);
  CHECK(a_pf < 0.15);
  CHECK(pf.back().covariance(0, 0) > 0);
  CHECK(pf.back().covariance(5, 5) > 0);
  CHECK(pf.back().covariance(2, 2) == 0);  // planar: z untouched
  std::map<std::string, int64_t> c;
  for (const auto& s : r.stages)
    if (s.name == "particle_filter")
      for (const auto& [k, v] : s.counters) c[k] = v;
  CHECK(c["updates"] > 100);
  CHECK(c["rejected"] == 0);
  // Same seed, same poses; another seed, other poses.
  const auto again = tools::replay_log(log, cfg);
  REQUIRE(again.fused_poses.at("pf").size() == pf.size());
  bool same = true;
  for (size_t i = 0; i < pf.size(); ++i)
    same = same && again.fused_poses.at("pf")[i].pose.position == pf[i].pose.position;
  CHECK(same);
  cfg.engine.filter.pf.seed = 6;
  const auto other = tools::replay_log(log, cfg);
  CHECK(other.fused_poses.at("pf").back().pose.position != pf.back().pose.position);
  std::remove(log.c_str());
}

TEST_CASE("particle filter stage: landmarks without ids are associated per particle") {
  const auto log = simulated_log("sextant_pf_unk_", 6, true);
  config::DaemonConfig cfg;
  cfg.engine.filter.type = engine::FilterType::kPf;
  cfg.engine.filter.pf.particles = 20;
  const auto r = tools::replay_log(log, cfg);
  std::map<std::string, int64_t> c;
  for (const auto& s : r.stages)
    if (s.name == "particle_filter")
      for (const auto& [k, v] : s.counters) c[k] = v;
  MESSAGE("associated " << c["associated"] << ", created " << c["new_landmarks"] << ", removed "
                        << c["removed_tentative"]);
  CHECK(c["associated"] > 500);
  CHECK(ate(r, "pf") < 0.5 * ate(r, "dead_reckoning"));
  std::remove(log.c_str());
}

TEST_CASE("particle filter config: filter.pf keys are read and checked with file and line") {
  const auto cfg = config::parse_daemon_config(
      "engine:\n  filter:\n    type: pf\n    pf:\n      particles: 250\n      resample_threshold: 0.3\n      seed: "
      "12\n",
      "t.yaml");
  CHECK(cfg.engine.filter.type == engine::FilterType::kPf);
  CHECK(cfg.engine.filter.pf.particles == 250);
  CHECK(cfg.engine.filter.pf.resample_threshold == 0.3);
  CHECK(cfg.engine.filter.pf.seed == 12);
  const auto error = [](const std::string& yaml) -> std::string {
    try {
      config::parse_daemon_config(yaml, "t.yaml");
    } catch (const config::ConfigError& e) {
      return e.what();
    }
    return "";
  };
  CHECK(error("engine:\n  filter:\n    type: pf\n    pf:\n      particles: 0\n").find("t.yaml:5") != std::string::npos);
  CHECK(error("engine:\n  filter:\n    pf:\n      resample_threshold: 2\n").find("resample_threshold") !=
        std::string::npos);
  CHECK(error("engine:\n  filter:\n    pf:\n      particle: 10\n").find("t.yaml:4") != std::string::npos);
  CHECK(error("engine:\n  filter:\n    type: fastslam\n").find("t.yaml:3") != std::string::npos);
}
