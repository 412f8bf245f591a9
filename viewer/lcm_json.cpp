#include "viewer/lcm_json.hpp"

namespace sextant::viewer {

const LcmJsonType* lcm_json_type_of(const uint8_t* data, size_t size) {
  if (size < 8) return nullptr;
  uint64_t hash = 0;
  for (int i = 0; i < 8; ++i) hash = (hash << 8) | data[i];
  for (const auto& t : lcm_json_types())
    if (static_cast<int64_t>(hash) == t.fingerprint) return &t;
  return nullptr;
}

const LcmJsonType* lcm_json_type_named(const std::string& name) {
  for (const auto& t : lcm_json_types())
    if (t.name == name) return &t;
  return nullptr;
}

}  // namespace sextant::viewer
