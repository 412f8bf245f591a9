// sextantd: the sextant state-estimation daemon.  See README.md and config/default.yaml.
#include "daemon/config/daemon_config.hpp"
#include "daemon/runtime/daemon.hpp"

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include <atomic>
#include <csignal>

namespace {
std::atomic<bool> g_stop{false};
static_assert(std::atomic<bool>::is_always_lock_free);
void on_signal(int) { g_stop.store(true); }
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"sextantd — real-time state estimation over LCM"};
  std::string config_path;
  std::string lcm_url;
  std::string record;
  std::string log_level = "info";
  app.add_option("--config", config_path, "YAML configuration (see config/default.yaml)")->required();
  auto* url_opt = app.add_option("--lcm-url", lcm_url, "LCM URL (overrides daemon.lcm_url)");
  auto* rec_opt = app.add_option("--record", record, "record every received message to this LCM log file");
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error"}));
  CLI11_PARSE(app, argc, argv);
  spdlog::set_level(spdlog::level::from_str(log_level));

  sextant::config::DaemonConfig config;
  try {
    config = sextant::config::load_daemon_config(config_path);
  } catch (const sextant::config::ConfigError& e) {
    spdlog::error("bad configuration: {}", e.what());
    return sextant::runtime::kExitConfig;
  }
  if (*url_opt) config.lcm_url = lcm_url;
  if (*rec_opt) config.record = record;

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  const int rc = sextant::runtime::run_daemon(config, g_stop);
  spdlog::info("sextantd exits with {}", rc);
  return rc;
}
