#pragma once
// sextant's LCM messages as JSON, for viewers that do not speak LCM (Foxglove, MCAP readers).
//
// Every struct of lcmtypes/sextant/*.lcm has a JSON form and a JSON Schema generated at build time from its
// definition (viewer/lcm_json_gen.py): an object with every field under its own name in declaration order (the
// `num_*` counts included), integers as integers, doubles as numbers, strings as strings, arrays as arrays, nested
// structs as objects.  A non-finite double (never in a valid message: the daemon rejects them) is written as the
// string "NaN", "Infinity" or "-Infinity" so that nothing is lost.  JSON -> LCM is the exact inverse: for every
// message whose strings are UTF-8 the bytes re-encoded from its JSON equal the original bytes.
#include <nlohmann/json.hpp>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace sextant::viewer {

/// JSON objects that keep their fields in declaration order.
using Json = nlohmann::ordered_json;

/// One message type: its name, fingerprint, schema and the two conversions.
struct LcmJsonType {
  std::string name;         // "sextant.fused_pose_t" (the schema name viewers show)
  int64_t fingerprint = 0;  // lcm-gen's getHash(): the first 8 bytes of every encoded message, big-endian
  std::string schema;       // JSON Schema of the JSON form
  /// Encoded bytes -> JSON; nullopt, with `error` saying why, when the bytes are not a well-formed message of this
  /// type (lengths checked before decoding: daemon/runtime/wire_layout.hpp).  Never throws.
  std::function<std::optional<Json>(const uint8_t* data, size_t size, std::string* error)> decode;
  /// JSON -> encoded bytes; throws std::runtime_error naming the field path ("fused_pose_t.position[2]: ...").
  std::function<std::vector<uint8_t>(const Json&)> encode;
};

/// Every sextant message type, by name.
const std::vector<LcmJsonType>& lcm_json_types();
/// The type whose fingerprint the bytes start with; nullptr when none (or fewer than 8 bytes).
const LcmJsonType* lcm_json_type_of(const uint8_t* data, size_t size);
/// The type named `name` ("sextant.fused_pose_t"); nullptr when none.
const LcmJsonType* lcm_json_type_named(const std::string& name);

}  // namespace sextant::viewer
