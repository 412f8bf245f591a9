#pragma once
// Loop-closure candidates for a new keyframe ("Graph-optimisation-based 3D visual odometry with Kinect",
// Sensors and Microsystems 2019):
// the new keyframe k (keyframes numbered 0, 1, 2, ... in order) is to be matched against
//   - "local" loops: each of the last n1 keyframes, k-1, k-2, ..., max(0, k-n1), in that order;
//   - "random" loops: n2 keyframes drawn uniformly at random without replacement from the earlier ones that are
//     not local, 0 .. k-n1-1 (all of them when there are at most n2), listed in increasing index.
// n2 = 2 n1 by default, as in that paper (they ran n1 = 3 / n2 = 6 and n1 = 4 / n2 = 8).
//
// Reproducibility: the random set of keyframe k is a pure function of (seed, k), the same on every platform and
// whatever the order of calls.  Draw, exactly:
//   std::seed_seq seq{lo32(seed), hi32(seed), lo32(k), hi32(k)};  std::mt19937_64 rng(seq);
//   Floyd's algorithm over the M = k - n1 candidates (R. Floyd, "Programming pearls: a sample of brilliance",
//   CACM 30(9), 1987):  S = {};  for j = M-m .. M-1:  t = uniform_index(rng, j+1);  S += (t in S ? j : t)
// with m = min(n2, M) and uniform_index the rejection draw of estimators/random/portable_random.hpp.
// std::seed_seq and std::mt19937_64 are specified exactly by the standard; uniform_index replaces
// std::uniform_int_distribution, whose output differs between standard libraries.
#include <cstdint>
#include <vector>

namespace sextant {

struct LoopProposalOptions {
  int n1 = 3;   // local loops per keyframe, >= 0
  int n2 = -1;  // random loops per keyframe, >= 0; -1: 2 n1
  uint64_t seed = 1;
};

struct LoopProposal {
  int64_t from = 0;     // the new keyframe
  int64_t to = 0;       // the earlier keyframe to match it against
  bool random = false;  // false: local loop
};

class LoopProposer {
 public:
  /// Throws std::invalid_argument unless n1 >= 0 and n2 >= -1.
  explicit LoopProposer(const LoopProposalOptions& options = {});

  /// The proposals of keyframe `new_keyframe_index` (>= 0; throws std::invalid_argument when negative): local
  /// ones first (nearest first), then random ones (increasing index).  Keyframe 0 gets none.
  std::vector<LoopProposal> propose(int64_t new_keyframe_index) const;

  int n1() const { return options_.n1; }
  int n2() const { return n2_; }  // with the default resolved
  uint64_t seed() const { return options_.seed; }

 private:
  LoopProposalOptions options_;
  int n2_ = 0;
};

}  // namespace sextant
