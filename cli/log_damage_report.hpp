#pragma once
// How the `sextant` commands that read an LCM log report what its checked reader skipped: a line on stderr naming the
// log and the damage (counts and the first offset), and exit code 4 for a damaged log unless the command was given
// --tolerate-damage (a truncated last event, as a killed recorder leaves it, is reported but is not damage).
#include "daemon/runtime/lcm_log.hpp"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <string>

namespace sextant::cli {

inline constexpr int kExitDamagedLog = 4;
inline constexpr const char* kTolerateDamageHelp =
    "exit 0 on a damaged log (corrupt events are skipped and counted either way; without this flag a damaged log "
    "makes the exit code 4)";

/// Reports `damage` of `log` for `tool`; throws CLI::RuntimeError(4) when the log is damaged and not tolerated.
inline void report_log_damage(const std::string& tool, const std::string& log, const runtime::LogDamage& damage,
                              bool tolerate) {
  if (const std::string d = damage.summary(); !d.empty())
    std::fprintf(stderr, "%s: %s: %s\n", tool.c_str(), log.c_str(), d.c_str());
  if (damage.damaged() && !tolerate) {
    std::fprintf(stderr, "%s: the log is damaged (its good events were used); --tolerate-damage accepts it\n",
                 tool.c_str());
    throw CLI::RuntimeError(kExitDamagedLog);
  }
}

}  // namespace sextant::cli
