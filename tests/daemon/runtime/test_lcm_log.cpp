// The LCM log reader: round trips with liblcm's writer, and damage found, skipped and counted instead of a crash
// (liblcm 1.3.1 segfaulted on a data length of 0x7fffffff) or a silent stop at the first corrupt header.
#include "daemon/runtime/lcm_log.hpp"
#include "daemon/runtime/recorder.hpp"

#include <doctest/doctest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

using namespace sextant;
using runtime::LogReader;
using runtime::LogRecord;

namespace {

std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("sextant_test_lcm_log_" + name)).string();
}

// A log of `n` events written by liblcm's writer; event k has channel "CH<k%3>" and k+1 bytes of data.
std::vector<uint8_t> sample_log(int n, std::vector<size_t>* starts = nullptr) {
  const auto path = temp_path("sample.lcm");
  {
    runtime::LogWriter w(path);
    for (int k = 0; k < n; ++k) {
      std::vector<uint8_t> data(static_cast<size_t>(k + 1), static_cast<uint8_t>(k));
      w.write_raw(1000 + k, "CH" + std::to_string(k % 3), data.data(), data.size());
    }
    w.flush();
  }
  std::ifstream in(path, std::ios::binary);
  std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::remove(path.c_str());
  if (starts != nullptr) {
    starts->clear();
    size_t pos = 0;
    for (int k = 0; k < n; ++k) {
      starts->push_back(pos);
      pos += 28 + ("CH" + std::to_string(k % 3)).size() + static_cast<size_t>(k + 1);
    }
  }
  return bytes;
}

std::vector<LogRecord> read(std::vector<uint8_t> bytes, runtime::LogDamage& damage) {
  auto r = LogReader::from_bytes(std::move(bytes));
  std::vector<LogRecord> out;
  while (auto e = r.next()) out.push_back(std::move(*e));
  damage = r.damage();
  return out;
}

void put_i32(std::vector<uint8_t>& b, size_t at, uint32_t v) {
  for (int i = 0; i < 4; ++i) b[at + static_cast<size_t>(i)] = static_cast<uint8_t>(v >> (24 - 8 * i));
}

}  // namespace

TEST_CASE("the reader reads back what liblcm's writer wrote, and so does a file") {
  const auto bytes = sample_log(20);
  runtime::LogDamage d;
  const auto events = read(bytes, d);
  REQUIRE(events.size() == 20);
  for (int k = 0; k < 20; ++k) {
    CHECK(events[static_cast<size_t>(k)].timestamp == 1000 + k);
    CHECK(events[static_cast<size_t>(k)].channel == "CH" + std::to_string(k % 3));
    CHECK(events[static_cast<size_t>(k)].data ==
          std::vector<uint8_t>(static_cast<size_t>(k + 1), static_cast<uint8_t>(k)));
  }
  CHECK_FALSE(d.damaged());
  CHECK(d.summary().empty());
  const auto path = temp_path("file.lcm");
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  runtime::LogDamage fd;
  CHECK(LogReader::read_all(path, &fd).size() == 20);
  CHECK_FALSE(fd.damaged());
  std::remove(path.c_str());
}

TEST_CASE("a data length of 0x7fffffff in a 52-byte file is a truncated event, not a crash") {
  std::vector<uint8_t> b(52, 0);
  put_i32(b, 0, 0xEDA1DA01);
  put_i32(b, 20, 4);           // channel length
  put_i32(b, 24, 0x7fffffff);  // data length
  b[28] = 'O', b[29] = 'D', b[30] = 'O', b[31] = 'M';
  runtime::LogDamage d;
  CHECK(read(b, d).empty());
  CHECK_FALSE(d.damaged());
  CHECK(d.truncated_tail_bytes == 52);
}

TEST_CASE("a corrupt length mid-file: the reader resynchronises on the next event and counts what it skipped") {
  std::vector<size_t> starts;
  auto b = sample_log(10, &starts);
  put_i32(b, starts[4] + 24, 0x00100000);  // event 4's data length: 1 MiB in a file of a few hundred bytes
  runtime::LogDamage d;
  const auto events = read(b, d);
  REQUIRE(events.size() == 9);  // every event but the damaged one
  CHECK(events[3].timestamp == 1003);
  CHECK(events[4].timestamp == 1005);
  CHECK(d.damaged());
  CHECK(d.bad_events == 1);
  CHECK(d.skipped_bytes == static_cast<int64_t>(starts[5] - starts[4]));
  CHECK(d.missing_event_numbers == 1);
  CHECK(d.summary().find("byte " + std::to_string(starts[4]) + ": data length 1048576") != std::string::npos);

  // Too short a length: the event does not end at a sync word; the same recovery.
  b = sample_log(10, &starts);
  put_i32(b, starts[6] + 24, 2);
  const auto short_events = read(b, d);
  CHECK(short_events.size() == 9);
  CHECK(d.bad_events == 1);
  CHECK(d.skipped_bytes == static_cast<int64_t>(starts[7] - starts[6]));
}

TEST_CASE("a flipped byte in a sync word or a channel length, and garbage between events, are skipped and counted") {
  std::vector<size_t> starts;
  auto b = sample_log(10, &starts);
  b[starts[2] + 1] ^= 0x10;  // sync word of event 2: event 1 is no longer followed by one either
  runtime::LogDamage d;
  auto events = read(b, d);
  CHECK(events.size() == 8);
  CHECK(d.bad_events == 1);
  CHECK(d.skipped_bytes == static_cast<int64_t>(starts[3] - starts[1]));

  b = sample_log(10, &starts);
  put_i32(b, starts[8] + 20, 5000);  // channel length beyond liblcm's bound
  events = read(b, d);
  CHECK(events.size() == 9);
  CHECK(d.summary().find("channel length 5000") != std::string::npos);

  b = sample_log(5, &starts);
  const std::vector<uint8_t> junk{1, 2, 3, 0xED, 0xA1, 4, 5};
  b.insert(b.begin() + static_cast<std::ptrdiff_t>(starts[3]), junk.begin(), junk.end());
  events = read(b, d);
  CHECK(events.size() == 4);  // event 2 is followed by junk, not by a sync word: it goes with the junk
  CHECK(d.skipped_bytes == static_cast<int64_t>(starts[3] - starts[2] + junk.size()));
}

TEST_CASE("a truncated last event is not damage, and every prefix of a log reads without error") {
  std::vector<size_t> starts;
  const auto b = sample_log(6, &starts);
  for (size_t n = 0; n <= b.size(); ++n) {
    runtime::LogDamage d;
    const auto events = read(std::vector<uint8_t>(b.begin(), b.begin() + static_cast<std::ptrdiff_t>(n)), d);
    size_t whole = 0;
    while (whole < starts.size() && (whole + 1 < starts.size() ? starts[whole + 1] : b.size()) <= n) ++whole;
    CHECK(events.size() == whole);
    CHECK_FALSE(d.damaged());
  }
}

TEST_CASE("a recorder never overwrites an existing file: it records next to it and says where") {
  const auto path = temp_path("rec.lcm");
  const auto second = temp_path("rec-1.lcm");
  std::remove(path.c_str());
  std::remove(second.c_str());
  { std::ofstream(path) << "earlier recording"; }
  {
    runtime::Recorder r(path, 16);
    CHECK(r.path() == second);
    r.record(LogRecord{5, "CH", {1, 2, 3}});
    r.close();
    CHECK(r.written() == 1);
  }
  std::ifstream in(path);
  std::string kept;
  std::getline(in, kept);
  CHECK(kept == "earlier recording");
  CHECK(LogReader::read_all(second).size() == 1);
  CHECK(runtime::create_unused(path) == temp_path("rec-2.lcm"));
  for (const auto& p : {path, second, temp_path("rec-2.lcm")}) std::remove(p.c_str());
}
