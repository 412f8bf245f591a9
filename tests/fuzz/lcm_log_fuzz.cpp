// Fuzz harness: the LCM log reader over arbitrary bytes.  Contract checked: no crash, no allocation beyond what the
// bytes hold, and the accounting adds up (every byte is in a good event, skipped, or the truncated tail).
#include "daemon/runtime/lcm_log.hpp"

#include <cstdint>
#include <cstdlib>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  auto reader = sextant::runtime::LogReader::from_bytes(std::vector<uint8_t>(data, data + size));
  int64_t good = 0;
  while (auto r = reader.next()) good += 28 + static_cast<int64_t>(r->channel.size() + r->data.size());
  const auto& d = reader.damage();
  if (good + d.skipped_bytes + d.truncated_tail_bytes != static_cast<int64_t>(size)) std::abort();
  if (d.bad_events < 0 || d.missing_event_numbers < 0) std::abort();
  return 0;
}
