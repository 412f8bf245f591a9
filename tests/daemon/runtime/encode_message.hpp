#pragma once
// Test helper: the LCM bytes of a message, as lcm-gen's encoder writes them (the encode must fill the buffer exactly).
#include <doctest/doctest.h>

#include <cstdint>
#include <vector>

template <class Msg>
std::vector<uint8_t> encode(const Msg& m) {
  std::vector<uint8_t> b(static_cast<size_t>(m.getEncodedSize()));
  REQUIRE(m.encode(b.data(), 0, static_cast<int>(b.size())) == static_cast<int>(b.size()));
  return b;
}
