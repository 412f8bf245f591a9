#pragma once
// A bounded, evenly spaced sample of a series that arrives one element at a time: every element while fewer than
// `capacity` were kept; past that, every other kept element is dropped and from then on only every 2nd (then 4th,
// 8th, ...) element is kept, so the sample always holds elements 0, s, 2s, ... of the series (s a power of two) and
// at most `capacity` of them.  Deterministic: the same series gives the same sample.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace sextant::tools {

class EvenSample {
 public:
  /// capacity 0: keep everything.
  explicit EvenSample(size_t capacity = 0) : capacity_(capacity) {}

  template <class T>
  void push(std::vector<T>& kept, T value) {
    if (capacity_ == 0) {
      kept.push_back(std::move(value));
      return;
    }
    if (seen_++ % stride_ != 0) return;
    kept.push_back(std::move(value));
    if (kept.size() <= capacity_) return;
    size_t w = 0;
    for (size_t r = 0; r < kept.size(); r += 2) kept[w++] = std::move(kept[r]);
    kept.resize(w);
    stride_ *= 2;
  }

 private:
  size_t capacity_;
  int64_t seen_ = 0, stride_ = 1;
};

}  // namespace sextant::tools
