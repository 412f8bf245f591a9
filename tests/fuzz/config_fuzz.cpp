// Fuzz harness: the YAML config reader.  Contract checked: a config or a ConfigError starting with the file's
// name; any other exception escapes and is a finding (a non-scalar key used to throw YAML::TypedBadConversion).
#include "daemon/config/daemon_config.hpp"

#include <cstdlib>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    (void)sextant::config::parse_daemon_config(text, "fuzz.yaml");
  } catch (const sextant::config::ConfigError& e) {
    if (std::string(e.what()).rfind("fuzz.yaml", 0) != 0) std::abort();
  }
  return 0;
}
