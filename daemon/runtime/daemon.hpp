#pragma once
// sextantd's runtime: one thread owns the LCM handle loop (decode, validate, record, route); each engine stage runs
// on its own thread behind a bounded queue; every output leaves through one Publisher; a status thread publishes
// SEXTANT_STATUS every `status_period_s`.  `run` returns when `stop` becomes true: intake stops, queues drain,
// stages finish, the recording is flushed, a last status goes out.
#include "daemon/config/daemon_config.hpp"

#include <atomic>
#include <string>

namespace sextant::runtime {

/// Exit codes of sextantd.
enum ExitCode : int { kExitOk = 0, kExitRuntime = 1, kExitConfig = 2, kExitBus = 3, kExitState = 4 };

/// The message printed when LCM cannot start on `url`, with how to fix it.
std::string bus_failure_help(const std::string& url);

/// Runs the daemon until `stop` is set; returns an ExitCode.
int run_daemon(const config::DaemonConfig& config, const std::atomic<bool>& stop);

}  // namespace sextant::runtime
