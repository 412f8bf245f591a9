#pragma once
// The message of the ConfigError that parsing a YAML text as "test.yaml" throws, or "" when it parses.
#include "daemon/config/daemon_config.hpp"

#include <string>

namespace sextant::test {

inline std::string config_error_of(const std::string& yaml) {
  try {
    config::parse_daemon_config(yaml, "test.yaml");
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "";
}

}  // namespace sextant::test
