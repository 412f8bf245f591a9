// sextantd: the sextant state-estimation daemon.  See README.md and config/default.yaml.
#include "daemon/config/daemon_config.hpp"
#include "daemon/engine/engine.hpp"
#include "daemon/runtime/daemon.hpp"
#include "daemon/runtime/version.hpp"

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <exception>

namespace {
std::atomic<bool> g_stop{false};
static_assert(std::atomic<bool>::is_always_lock_free);
void on_signal(int) { g_stop.store(true); }

// --check-config: everything startup does short of touching the bus (parse, validate, build the engine's stages).
// Prints "FILE: ok" and returns 0, or the error ("FILE:LINE:COLUMN: ...") on stderr and returns 2.
int check_config(const std::string& path) {
  try {
    const auto config = sextant::config::load_daemon_config(path);
    const sextant::engine::Engine engine(config.engine);
    std::string stages;
    for (const auto& stage : engine.stages()) stages += (stages.empty() ? "" : ", ") + std::string(stage->name());
    std::printf("%s: ok (stages: %s; primary estimator: %s)\n", path.c_str(), stages.empty() ? "none" : stages.c_str(),
                engine.primary_estimator().c_str());
    return sextant::runtime::kExitOk;
  } catch (const sextant::config::ConfigError& e) {
    std::fprintf(stderr, "%s\n", e.what());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", path.c_str(), e.what());
  }
  return sextant::runtime::kExitConfig;
}
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"sextantd — real-time state estimation over LCM"};
  std::string config_path;
  std::string lcm_url;
  std::string record;
  std::string log_level = "info";
  std::string check_path;
  app.set_version_flag("--version", sextant::version());
  auto* config_opt = app.add_option("--config", config_path, "YAML configuration (see config/default.yaml)");
  app.add_option("--check-config", check_path, "validate this configuration and exit: 0, or 2 with FILE:LINE on stderr")
      ->excludes(config_opt);
  auto* url_opt = app.add_option("--lcm-url", lcm_url, "LCM URL (overrides daemon.lcm_url)");
  auto* rec_opt = app.add_option("--record", record,
                                 "record every received message to this LCM log file (an existing file is kept: the "
                                 "recording then goes to STEM-1.EXT, STEM-2.EXT, ...)");
  std::string state_dir;
  bool discard_bad_state = false;
  auto* state_opt = app.add_option("--state-dir", state_dir,
                                   "save the estimators' state in this directory and resume from it at start "
                                   "(overrides daemon.state_dir; README, \"State directory\")");
  app.add_flag("--discard-bad-state", discard_bad_state,
               "a state file that cannot be used (damaged, other version or config) is renamed aside and the daemon "
               "starts fresh, instead of exiting with 4");
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error"}));
  CLI11_PARSE(app, argc, argv);
  if (!check_path.empty()) return check_config(check_path);
  if (config_path.empty()) {
    std::fprintf(stderr, "sextantd: --config FILE is required (or --check-config FILE, --version)\n");
    return sextant::runtime::kExitConfig;
  }
  spdlog::set_level(spdlog::level::from_str(log_level));
  spdlog::info("sextantd {}", sextant::version());

  sextant::config::DaemonConfig config;
  try {
    config = sextant::config::load_daemon_config(config_path);
  } catch (const sextant::config::ConfigError& e) {
    spdlog::error("bad configuration: {}", e.what());
    return sextant::runtime::kExitConfig;
  }
  if (*url_opt) config.lcm_url = lcm_url;
  if (*rec_opt) config.record = record;
  if (*state_opt) config.state_dir = state_dir;
  config.discard_bad_state = discard_bad_state;

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  const int rc = sextant::runtime::run_daemon(config, g_stop);
  spdlog::info("sextantd exits with {}", rc);
  return rc;
}
