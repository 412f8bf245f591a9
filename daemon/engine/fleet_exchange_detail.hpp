#pragma once
// What the exchange's two sides (fleet_outbox.cpp, fleet_inbox.cpp) share beyond fleet_exchange.hpp.
#include <cstddef>
#include <cstdint>

namespace sextant::engine::fleet::detail {

constexpr size_t kMegabyte = size_t{1} << 20;
// A stream's numbers stay far from overflow: a sender's `first` + count beyond this is out of any window.
constexpr int64_t kMaxSeq = int64_t{1} << 62;

/// Seconds as microseconds (the exchange's clock).
inline int64_t micros(double seconds) { return static_cast<int64_t>(seconds * 1e6); }

}  // namespace sextant::engine::fleet::detail
