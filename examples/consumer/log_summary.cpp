// log_summary LOG.lcm: per channel, the number of events and how many decode as an odometry_t that sextantd would
// accept (its own validation, daemon/runtime/codec.hpp); prints one line per channel, "CHANNEL EVENTS ACCEPTED".
// Links sextant::runtime (LCM logs, the codec, the generated message types).
#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/lcm_log.hpp"

#include <cstdio>
#include <exception>
#include <map>
#include <utility>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s LOG.lcm\n", argv[0]);
    return 2;
  }
  std::map<std::string, std::pair<long, long>> channels;  // events, accepted odometry
  try {
    sextant::runtime::LogReader reader(argv[1]);
    while (auto r = reader.next()) {
      auto& [events, accepted] = channels[r->channel];
      ++events;
      const auto d =
          sextant::runtime::decode_event(sextant::runtime::InputKind::kOdometry, r->data.data(), r->data.size());
      if (std::holds_alternative<sextant::engine::Event>(d)) ++accepted;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
  for (const auto& [name, c] : channels) std::printf("%s %ld %ld\n", name.c_str(), c.first, c.second);
  return 0;
}
