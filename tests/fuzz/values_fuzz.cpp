// Fuzz harness: the value fuzzer (test_hostile_values.cpp) guided by coverage.  A clean simulated body and a victim
// body go through the intake and every stage of the default engine; the input's bytes say which of the victim's
// messages are mutated and how (which fields of its odometry or sightings take which extreme but
// finite values, which flags flip, which stamps jump; hostile_engine.hpp).  The first byte picks the EKF or the
// particle filter.  Contract checked: every published pose is finite with a positive semi-definite covariance, and
// the clean body's poses are those of a run without the victim.  Work per input is bounded by libFuzzer's -timeout.
#include "daemon/runtime/hostile_engine.hpp"

#include <cstdint>
#include <cstdlib>
#include <vector>

using namespace sextant::hostile;

namespace {

constexpr double kSeconds = 8;    // of each simulated run: a few keyframes per body
constexpr int kMaxMutated = 120;  // victim messages mutated at most (of about 500)

// The input's bytes as choices: a number in [0, n) from one byte (four when n > 256); 0 once they are used up.
struct Bytes {
  const uint8_t* p;
  size_t left;
  size_t next(size_t n) {
    uint32_t v = 0;
    for (int i = 0; i < (n > 256 ? 4 : 1) && left > 0; ++i, ++p, --left) v = v << 8 | *p;
    return v % n;
  }
};

const std::vector<Record>& clean() {
  static const auto run = simulated_run("clean", kSeconds, 5);
  return run;
}

const std::vector<Record>& victim() {
  static const auto run = simulated_run("victim", kSeconds, 6, false, /*loops=*/true);
  return run;
}

// The clean body's poses when it is alone, by filter.
const std::vector<sextant::engine::FusedPose>& alone(bool pf) {
  static const auto poses = [] {
    std::vector<std::vector<sextant::engine::FusedPose>> out;
    for (bool f : {false, true}) {
      Run r(f);
      for (const auto& m : clean()) r.feed(m);
      out.push_back(r.of("clean"));
    }
    return out;
  }();
  return poses[pf ? 1 : 0];
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const bool pf = data[0] & 1;
  Bytes bytes{data + 1, size - 1};
  const Choose choose = [&](size_t n) { return bytes.next(n); };
  // A message is mutated when its byte is below 64 (a quarter of random bytes), none once the bytes are used up.
  const auto hit = [&] { return bytes.left > 0 && bytes.next(256) < 64; };
  int mutated = 0;
  const auto input = mixed(clean(), victim(), hit, choose, kMaxMutated, mutated);
  Run run(pf);
  for (const auto& r : input) run.feed(r);
  if (run.unhealthy != 0) std::abort();
  if (differing_poses(run.of("clean"), alone(pf)) != 0) std::abort();
  return 0;
}
