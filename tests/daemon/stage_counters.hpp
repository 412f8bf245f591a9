#pragma once
// A stage's counter by name, for the daemon's tests: from engine::Counters, a Stage (its counters()) or a runner's
// StageStatus.  A name the counters do not hold fails the test, so that a renamed counter cannot read as 0 or -1 and
// pass; has_counter says whether one is there.
#include "daemon/engine/stage.hpp"
#include "daemon/runtime/stage_runner.hpp"

#include <doctest/doctest.h>

#include <string>

namespace sextant::stage_counters {

inline bool has_counter(const engine::Counters& counters, const std::string& name) {
  for (const auto& [n, v] : counters)
    if (n == name) return true;
  return false;
}

inline int64_t counter(const engine::Counters& counters, const std::string& name) {
  for (const auto& [n, v] : counters)
    if (n == name) return v;
  FAIL("no counter '" << name << "'");
  return -1;
}

inline int64_t counter(const engine::Stage& stage, const std::string& name) { return counter(stage.counters(), name); }

inline int64_t counter(const runtime::StageStatus& status, const std::string& name) {
  return counter(status.counters, name);
}

}  // namespace sextant::stage_counters
