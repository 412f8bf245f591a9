#pragma once
// The codec's validation kernel, shared by its decoders (codec.cpp: the sensors' inputs, codec_fleet.cpp: the fleet's
// messages): a refusal carries its reason and the field it names up to the decoder's entry point, where guarded()
// turns it into a Rejection.  Thrown and caught inside the codec only.
#include "daemon/runtime/codec.hpp"

#include <cmath>
#include <cstddef>
#include <exception>
#include <sstream>
#include <string>

namespace sextant::runtime::codec_validation {

struct Invalid {
  std::string reason;
  std::string message;
};

[[noreturn]] inline void fail(const std::string& reason, const std::string& message) { throw Invalid{reason, message}; }

/// Refuses (non_finite) the first of v[0..n) that is not finite, naming `field` (with its index when n > 1).
inline void check_finite(const double* v, int n, const std::string& field) {
  for (int i = 0; i < n; ++i)
    if (!std::isfinite(v[i])) {
      std::ostringstream s;
      s << field;
      if (n > 1) s << "[" << i << "]";
      s << ": not finite (" << v[i] << ")";
      fail("non_finite", s.str());
    }
}

/// A name's length at most (a body, a sender, a frame, a daemon), characters.
inline constexpr size_t kMaxNameLength = 256;

/// Refuses (invalid) a name longer than kMaxNameLength or holding a control character (names reach logs, channel
/// and topic names), and an empty one unless `may_be_empty`.
inline void check_name(const std::string& s, const std::string& field, bool may_be_empty = true) {
  if (s.empty() && !may_be_empty) fail("invalid", field + ": empty");
  if (s.size() > kMaxNameLength) fail("invalid", field + ": longer than 256 characters");
  for (unsigned char c : s)
    if (c < 0x20 || c == 0x7f) fail("invalid", field + ": a control character");
}

/// f(), or the Rejection of the refusal it threw.
template <class F>
Decoded guarded(F&& f) {
  try {
    return f();
  } catch (const Invalid& e) {
    return Rejection{e.reason, e.message};
  } catch (const std::exception& e) {
    // Validation itself must never take the daemon down (an allocation failing, an Eigen assertion turned
    // exception): the message is refused like any invalid one.
    return Rejection{"invalid", e.what()};
  }
}

}  // namespace sextant::runtime::codec_validation
