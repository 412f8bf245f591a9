// The replay's order: a log's records by the time their messages carry, ties in file order, whatever the memory budget
// for records read ahead of their turn; a message stamped before everything else at the end of a log holds at most the
// budget in memory (the rest is read a second time), where it used to hold the whole log.
#include "replay/time_ordered_log.hpp"

#include "daemon/runtime/lcm_log.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <numeric>
#include <random>
#include <string>
#include <utility>
#include <vector>

using namespace sextant;

namespace {

std::string temp_log(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("sextant_time_order_" + name + ".lcm")).string();
}

/// A message of `size` bytes whose utime field (after the 8-byte fingerprint, big-endian) is `utime`; its last bytes
/// say which record it is.
std::vector<uint8_t> message(int64_t utime, uint32_t id, size_t size = 24) {
  std::vector<uint8_t> b(size, 0xAB);
  for (int i = 0; i < 8; ++i)
    b[static_cast<size_t>(8 + i)] = static_cast<uint8_t>(static_cast<uint64_t>(utime) >> (56 - 8 * i));
  for (int i = 0; i < 4; ++i) b[b.size() - 4 + static_cast<size_t>(i)] = static_cast<uint8_t>(id >> (24 - 8 * i));
  return b;
}

uint32_t id_of(const runtime::LogRecord& r) {
  uint32_t id = 0;
  for (size_t i = r.data.size() - 4; i < r.data.size(); ++i) id = (id << 8) | r.data[i];
  return id;
}

/// The ids in the order `log` hands its records over.
std::vector<uint32_t> replayed(tools::TimeOrderedLog& log) {
  std::vector<uint32_t> ids;
  log.for_each([&](const runtime::LogRecord& r) { ids.push_back(id_of(r)); });
  return ids;
}

}  // namespace

TEST_CASE("a log's records come in the order of their own stamps, ties in file order, whatever the memory budget") {
  const std::string path = temp_log("shuffled");
  std::mt19937 rng(7);
  std::vector<std::pair<int64_t, uint32_t>> written;  // (the stamp the replay goes by, id), in file order
  {
    runtime::LogWriter w(path);
    for (uint32_t id = 0; id < 300; ++id) {
      const int64_t log_stamp = 1'000'000 + 1'000 * id;  // arrival order
      if (id % 50 == 17) {                               // too short to carry a utime: the log's stamp is its time
        w.write_raw(log_stamp, "SHORT", message(0, id, 12).data(), 12);
        written.emplace_back(log_stamp, id);
        continue;
      }
      // Stamps jittered against arrival (up to 40 ms back), with ties; the last record was stamped before any other.
      const int64_t utime = id == 299 ? 5 : log_stamp - 1'000 * static_cast<int64_t>(rng() % 40) / 4 * 4;
      const auto b = message(utime, id, 24 + id % 7);
      w.write_raw(log_stamp, "MSG", b.data(), b.size());
      written.emplace_back(utime, id);
    }
  }
  // The order, computed here on its own: a stable sort of the file order by stamp.
  std::vector<std::pair<int64_t, uint32_t>> sorted = written;
  std::stable_sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<uint32_t> expected;
  for (const auto& [t, id] : sorted) expected.push_back(id);
  REQUIRE(expected.front() == 299);
  std::vector<uint32_t> file_order(expected.size());
  std::iota(file_order.begin(), file_order.end(), 0U);
  REQUIRE(expected != file_order);

  for (const size_t budget : {size_t{0}, size_t{1000}, tools::TimeOrderedLog::kHeldBytes}) {
    CAPTURE(budget);
    tools::TimeOrderedLog log(path, budget);
    CHECK(log.records() == 300);
    CHECK_FALSE(log.damage().damaged());
    CHECK(replayed(log) == expected);
    CHECK(log.held_bytes_peak() <= budget);
    if (budget == 0) CHECK(log.read_again() == 299);  // everything before the last record, read again in its turn
    if (budget == tools::TimeOrderedLog::kHeldBytes) CHECK(log.read_again() == 0);
    CHECK(replayed(log) == expected);  // a second pass is the same
  }
  std::remove(path.c_str());
}

TEST_CASE("one message stamped before all others at the end of a long log holds at most the budget in memory") {
  // A sender whose clock said 1970 once, at the end of the run: the replay starts with that message, so every record
  // before it in the file waits for its turn.  They used to wait in memory (the whole log); now at most the budget
  // does and the rest is read again from the file.
  const std::string path = temp_log("late_zero");
  constexpr uint32_t kRecords = 4000;
  constexpr size_t kSize = 1000, kBudget = 200'000;
  {
    runtime::LogWriter w(path);
    for (uint32_t id = 0; id < kRecords; ++id) {
      const auto b = message(1'700'000'000'000'000 + 10'000 * int64_t{id}, id, kSize);
      w.write_raw(1'700'000'000'000'000 + 10'000 * int64_t{id}, "ODOMETRY", b.data(), b.size());
    }
    const auto zero = message(0, kRecords, kSize);
    w.write_raw(1'700'000'000'000'000 + 10'000 * int64_t{kRecords}, "ODOMETRY", zero.data(), zero.size());
  }
  std::vector<uint32_t> expected(kRecords + 1);
  expected[0] = kRecords;
  std::iota(expected.begin() + 1, expected.end(), 0U);

  tools::TimeOrderedLog bounded(path, kBudget);
  CHECK(replayed(bounded) == expected);
  CHECK(bounded.held_bytes_peak() <= kBudget);
  CHECK(bounded.held_bytes_peak() > kBudget - 2 * kSize);  // the budget is used, then the rest is read again
  CHECK(bounded.read_again() > kRecords - kBudget / kSize);
  CHECK(bounded.read_again() < kRecords);

  tools::TimeOrderedLog unbounded(path, size_t{1} << 40);  // what the replay did before: the whole log held
  CHECK(replayed(unbounded) == expected);
  CHECK(unbounded.held_bytes_peak() > kRecords * kSize);
  CHECK(unbounded.read_again() == 0);
  std::remove(path.c_str());
}
