#pragma once
// LCM's wire layout of sextant's messages, walked over untrusted bytes before lcm-gen's generated decode runs.
//
// lcm-gen 1.3.1's decoders trust the lengths they read: a string whose length field is 0 (or negative) makes
// `std::string::assign(p, len - 1)` throw std::length_error, and a variable array is `resize`d to the count on the
// wire before a single element is read (0x7fffffff elements: bad_alloc; 20 million landmark observations: 2 GB).
// `wire_error` reads the encoding as LCM defines it (big-endian; a string is an int32 length that counts its
// terminating NUL, then the bytes and the NUL; a variable array's count is an earlier int32 field; nested structs
// follow each other without fingerprints) and refuses, naming the field and byte offset, any length that does not
// fit in the bytes that are left, any string without its NUL and any count outside [0, the field's maximum].
// The layouts mirror lcmtypes/sextant/*.lcm; tests/daemon/runtime/test_wire_layout.cpp checks each against lcm-gen's
// encoder (the encoded size of random messages, and every truncation refused).
#include <sextant/bearing_scan_t.hpp>
#include <sextant/fleet_contribution_t.hpp>
#include <sextant/fleet_control_t.hpp>
#include <sextant/fused_pose_t.hpp>
#include <sextant/geo_pose_t.hpp>
#include <sextant/gnss_t.hpp>
#include <sextant/imu_t.hpp>
#include <sextant/landmarks_t.hpp>
#include <sextant/loop_closure_t.hpp>
#include <sextant/match_request_t.hpp>
#include <sextant/odometry_t.hpp>
#include <sextant/status_t.hpp>
#include <sextant/landmark_map_t.hpp>
#include <sextant/targets_t.hpp>
#include <sextant/trajectory_t.hpp>
#include <sextant/truth_t.hpp>

#include <cstddef>
#include <cstdint>
#include <exception>
#include <optional>
#include <string>
#include <vector>

namespace sextant::runtime {

struct WireLayout;

struct WireField {
  enum class Kind {
    kFixed,   // `bytes` bytes (int64: 8, boolean: 1, double[36]: 288)
    kString,  // int32 length n >= 1, then n bytes ending in NUL
    kCount,   // int32 count of the next kArray field, in [0, max_count]
    kArray,   // `count` elements of `element` (the count is the last kCount before this field)
  };
  std::string name;
  Kind kind = Kind::kFixed;
  size_t bytes = 0;
  int32_t max_count = 0;
  const WireLayout* element = nullptr;
};

struct WireLayout {
  std::string type;  // "landmarks_t"
  std::vector<WireField> fields;
  /// The smallest encoding of one value (every array empty, every string ""); bounds what a count can claim.
  size_t min_size() const;
};

/// Why bytes are not a well-formed encoding: `reason` "decode" (a length that does not fit, a string without its
/// NUL) or "too_large" (a count above the field's maximum); `message` names the field and the byte offset.
struct WireError {
  std::string reason;
  std::string message;
};

/// Walks `size` bytes after the 8-byte fingerprint (which the caller checks) against `layout`; nullopt when every
/// length fits.  Trailing bytes after the last field are allowed (as LCM allows them).
std::optional<WireError> wire_error(const WireLayout& layout, const void* data, size_t size);

/// The layout of each message type that arrives from outside: the daemon's inputs, ground truth and match requests
/// in logs and on the bus, and the daemon's outputs as tools read them (`sextant watch`, logs, the Python module).
/// Input array maxima are the codec's (kMaxObservationsPerMessage, kMaxDetectionsPerScan).
template <class Msg>
const WireLayout& wire_layout();
template <>
const WireLayout& wire_layout<sextant::odometry_t>();
template <>
const WireLayout& wire_layout<sextant::landmarks_t>();
template <>
const WireLayout& wire_layout<sextant::bearing_scan_t>();
template <>
const WireLayout& wire_layout<sextant::loop_closure_t>();
template <>
const WireLayout& wire_layout<sextant::imu_t>();
template <>
const WireLayout& wire_layout<sextant::gnss_t>();
template <>
const WireLayout& wire_layout<sextant::truth_t>();
template <>
const WireLayout& wire_layout<sextant::match_request_t>();
template <>
const WireLayout& wire_layout<sextant::fused_pose_t>();
template <>
const WireLayout& wire_layout<sextant::geo_pose_t>();
template <>
const WireLayout& wire_layout<sextant::status_t>();
template <>
const WireLayout& wire_layout<sextant::trajectory_t>();
template <>
const WireLayout& wire_layout<sextant::targets_t>();
template <>
const WireLayout& wire_layout<sextant::landmark_map_t>();
template <>
const WireLayout& wire_layout<sextant::fleet_contribution_t>();
template <>
const WireLayout& wire_layout<sextant::fleet_control_t>();

/// Whether `wire_layout<Msg>()` exists (safe_decode needs it).
template <class Msg>
inline constexpr bool kHasWireLayout = false;
template <>
inline constexpr bool kHasWireLayout<sextant::odometry_t> = true;
template <>
inline constexpr bool kHasWireLayout<sextant::landmarks_t> = true;
template <>
inline constexpr bool kHasWireLayout<sextant::bearing_scan_t> = true;
template <>
inline constexpr bool kHasWireLayout<sextant::loop_closure_t> = true;
template <>
inline constexpr bool kHasWireLayout<sextant::imu_t> = true;
template <>
inline constexpr bool kHasWireLayout<sextant::gnss_t> = true;
template <>
inline constexpr bool kHasWireLayout<sextant::truth_t> = true;
template <>
inline constexpr bool kHasWireLayout<sextant::match_request_t> = true;
template <>
inline constexpr bool kHasWireLayout<sextant::fused_pose_t> = true;
template <>
inline constexpr bool kHasWireLayout<sextant::geo_pose_t> = true;
template <>
inline constexpr bool kHasWireLayout<sextant::status_t> = true;
template <>
inline constexpr bool kHasWireLayout<sextant::trajectory_t> = true;
template <>
inline constexpr bool kHasWireLayout<sextant::targets_t> = true;
template <>
inline constexpr bool kHasWireLayout<sextant::landmark_map_t> = true;
template <>
inline constexpr bool kHasWireLayout<sextant::fleet_contribution_t> = true;
template <>
inline constexpr bool kHasWireLayout<sextant::fleet_control_t> = true;

/// Decodes untrusted bytes as `Msg`: the fingerprint, then the layout walk (for the types that have one), then
/// lcm-gen's decode with anything it throws caught.  nullopt on success, else what is wrong ("fingerprint", "decode" or "too_large").
template <class Msg>
std::optional<WireError> safe_decode(const void* data, size_t size, Msg& msg) {
  if (size < 8)
    return WireError{"decode", Msg::getTypeName() + std::string(": shorter than an LCM fingerprint (") +
                                   std::to_string(size) + " bytes)"};
  int64_t hash = 0;
  if (__int64_t_decode_array(data, 0, 8, &hash, 1) != 8 || hash != Msg::getHash())
    return WireError{"fingerprint", std::string("fingerprint does not match ") + Msg::getTypeName()};
  if (size > static_cast<size_t>(INT32_MAX))
    return WireError{"too_large", Msg::getTypeName() + std::string(": message of ") + std::to_string(size) + " bytes"};
  if constexpr (kHasWireLayout<Msg>) {
    if (auto e = wire_error(wire_layout<Msg>(), data, size)) return e;
  }
  try {
    if (msg.decode(data, 0, static_cast<int>(size)) < 0)
      return WireError{"decode", std::string("cannot decode ") + Msg::getTypeName() + " (truncated or corrupt)"};
  } catch (const std::exception& e) {
    return WireError{"decode", std::string("cannot decode ") + Msg::getTypeName() + ": " + e.what()};
  }
  return std::nullopt;
}

}  // namespace sextant::runtime
