// Real-time republishing of a log (on LCM's in-process memq:// bus): ordinary gaps between messages are kept, and
// one message stamped decades before the others (a sender's clock at zero) does not hold the rest back.
#include "replay/realtime_player.hpp"

#include "daemon/runtime/lcm_log.hpp"

#include <doctest/doctest.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

using namespace sextant;

namespace {

/// A log of messages whose utime fields (after the 8-byte fingerprint, big-endian) are `utimes`, in that file order.
std::string log_of(const std::string& name, const std::vector<int64_t>& utimes) {
  const std::string path = (std::filesystem::temp_directory_path() / ("sextant_realtime_" + name + ".lcm")).string();
  runtime::LogWriter w(path);
  int64_t stamp = 1'700'000'000'000'000;
  for (const int64_t t : utimes) {
    std::vector<uint8_t> b(24, 0);
    for (int i = 0; i < 8; ++i)
      b[static_cast<size_t>(8 + i)] = static_cast<uint8_t>(static_cast<uint64_t>(t) >> (56 - 8 * i));
    w.write_raw(stamp += 1'000, "MSG", b.data(), b.size());
  }
  return path;
}

double seconds_to_play(const std::string& path, const tools::RealtimeOptions& o, tools::RealtimePlayback& out) {
  const auto start = std::chrono::steady_clock::now();
  out = tools::play_realtime(path, o);
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

TEST_CASE("realtime playback keeps the gaps between messages, divided by the speed") {
  constexpr int64_t kT = 1'700'000'000'000'000;
  const std::string path = log_of("paced", {kT, kT + 150'000, kT + 300'000});
  tools::RealtimePlayback out;
  const double took = seconds_to_play(path, {1.0, 10.0, "memq://"}, out);
  CHECK(out.published == 3);
  CHECK(out.gaps_shortened == 0);
  CHECK(took >= 0.3);
  CHECK(took < 2.0);
  const double twice = seconds_to_play(path, {2.0, 10.0, "memq://"}, out);
  CHECK(twice >= 0.15);
  CHECK(twice < took);
  std::remove(path.c_str());
}

TEST_CASE("one message stamped decades before the others plays first and does not hold the log back") {
  constexpr int64_t kT = 1'700'000'000'000'000;
  // Recorded last, stamped 1 us after 1970: it plays first, then 54 years of log time to the next message.
  const std::string path = log_of("clock_at_zero", {kT, kT + 100'000, kT + 200'000, 1});
  tools::RealtimePlayback out;
  const double took = seconds_to_play(path, {1.0, 0.5, "memq://"}, out);
  CHECK(out.published == 4);
  CHECK(out.gaps_shortened == 1);
  CHECK(out.log_seconds_skipped == doctest::Approx((kT - 1) * 1e-6 - 0.5));
  CHECK(took >= 0.7);  // 0.5 s for the shortened gap, then the two ordinary ones
  CHECK(took < 3.0);
  std::remove(path.c_str());
}
