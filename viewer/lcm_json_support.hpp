#pragma once
// What the generated JSON conversions (viewer/lcm_json_gen.py) are written with: one value to JSON, one JSON value
// back with its type and range checked, and the path of the field being read for the error message.
#include "daemon/runtime/wire_layout.hpp"
#include "viewer/lcm_json.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>

namespace sextant::viewer {

/// Where a value sits in a message: "fused_pose_t.position[2]".  Built on the stack while reading; turned into
/// text only for an error.
struct Where {
  const Where* parent = nullptr;
  const char* name = nullptr;  // a field name, or nullptr for an array element
  int index = -1;
  std::string str() const {
    std::string s = parent ? parent->str() : std::string();
    if (name) return s.empty() ? std::string(name) : s + "." + name;
    return s + "[" + std::to_string(index) + "]";
  }
};

[[noreturn]] inline void json_error(const Where& at, const std::string& what) {
  throw std::runtime_error(at.str() + ": " + what);
}

inline Json json_value(const std::string& v) { return Json(v); }
template <class T>
Json json_value(T v) {
  if constexpr (std::is_floating_point_v<T>) {
    if (std::isnan(v)) return Json("NaN");
    if (std::isinf(v)) return Json(v > 0 ? "Infinity" : "-Infinity");
    return Json(static_cast<double>(v));
  } else {
    return Json(static_cast<int64_t>(v));
  }
}

/// An LCM boolean (lcm-gen's C++ holds it in an int8_t).
inline void read_boolean(const Json& j, int8_t& v, const Where& at) {
  if (!j.is_boolean()) json_error(at, "expected true or false");
  v = j.get<bool>() ? 1 : 0;
}
inline void read_value(const Json& j, std::string& v, const Where& at) {
  if (!j.is_string()) json_error(at, "expected a string");
  v = j.get<std::string>();
  // LCM's encoder ends a string at its first NUL: the message would be shorter than its stated size.
  if (v.find('\0') != std::string::npos) json_error(at, "holds a NUL character (\\u0000)");
}
template <class T>
void read_value(const Json& j, T& v, const Where& at) {
  if constexpr (std::is_floating_point_v<T>) {
    if (j.is_number()) {
      v = static_cast<T>(j.get<double>());
    } else if (j.is_string() && (j == "NaN" || j == "Infinity" || j == "-Infinity")) {
      const auto s = j.get<std::string>();
      v = s == "NaN" ? std::numeric_limits<T>::quiet_NaN()
                     : (s[0] == '-' ? -std::numeric_limits<T>::infinity() : std::numeric_limits<T>::infinity());
    } else {
      json_error(at, "expected a number");
    }
  } else {
    if (j.is_number_unsigned()) {
      const auto u = j.get<uint64_t>();
      if (u > static_cast<uint64_t>(std::numeric_limits<T>::max())) json_error(at, "integer out of range");
      v = static_cast<T>(u);
    } else if (j.is_number_integer()) {
      const auto i = j.get<int64_t>();
      if (i < static_cast<int64_t>(std::numeric_limits<T>::min()) ||
          i > static_cast<int64_t>(std::numeric_limits<T>::max()))
        json_error(at, "integer out of range");
      v = static_cast<T>(i);
    } else {
      json_error(at, "expected an integer");
    }
  }
}

inline void require_object(const Json& j, const Where& at) {
  if (!j.is_object()) json_error(at, "expected an object");
}
inline const Json& member(const Json& j, const Where& at) {
  const auto it = j.find(at.name);
  if (it == j.end()) json_error(at, "missing");
  return *it;
}
inline void require_array(const Json& j, int64_t size, const Where& at) {
  if (!j.is_array()) json_error(at, "expected an array");
  if (static_cast<int64_t>(j.size()) != size)
    json_error(at, "has " + std::to_string(j.size()) + " elements, its size says " + std::to_string(size));
}

/// The registry entry of one lcm-gen type from its generated conversions.
template <class Msg, class ToJson, class FromJson>
LcmJsonType make_lcm_json_type(const char* name, const char* schema, ToJson to_json, FromJson from_json) {
  LcmJsonType t;
  t.name = name;
  t.fingerprint = Msg::getHash();
  t.schema = schema;
  t.decode = [to_json](const uint8_t* data, size_t size, std::string* error) -> std::optional<Json> {
    Msg m;
    if (auto e = runtime::safe_decode(data, size, m)) {
      if (error) *error = e->message;
      return std::nullopt;
    }
    return to_json(m);
  };
  t.encode = [from_json](const Json& j) {
    Msg m;
    const std::string root = Msg::getTypeName();
    from_json(j, m, Where{nullptr, root.c_str()});
    std::vector<uint8_t> buf(static_cast<size_t>(m.getEncodedSize()));
    if (m.encode(buf.data(), 0, static_cast<int>(buf.size())) < 0)
      throw std::runtime_error(root + ": cannot encode (an array shorter than its count)");
    return buf;
  };
  return t;
}

}  // namespace sextant::viewer
