// MCAP writer and reader: what is written reads back in order with the summary's statistics and indexes pointing
// at the records they name; every CRC catches a flipped byte; a cut file is refused by name.
#include "viewer/mcap.hpp"
#include "temp_path.hpp"

#include <doctest/doctest.h>

#include <fstream>
#include <iterator>
#include <string>

using namespace sextant::viewer;
using sextant::viewer::test::temp_path;

namespace {

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}
void dump(const std::string& path, const std::string& bytes) { std::ofstream(path, std::ios::binary) << bytes; }

uint64_t le64(const std::string& b, size_t at) {
  uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= static_cast<uint64_t>(static_cast<uint8_t>(b[at + i])) << (8 * i);
  return v;
}

/// 3 channels (two sharing a schema, one without), 600 messages with times out of order, small chunks.
std::string write_sample(const std::string& name) {
  const auto path = temp_path(name);
  McapWriterOptions o;
  o.chunk_size = 4096;
  McapWriter w(path, o);
  const auto s1 = w.add_schema("sextant.a", "jsonschema", R"({"type":"object"})");
  const auto c0 = w.add_channel(s1, "A", "json", {{"lcm_channel", "A"}});
  const auto c1 = w.add_channel(s1, "B", "json");
  const auto c2 = w.add_channel(0, "lcm_raw/C", "lcm");
  for (int i = 0; i < 600; ++i) {
    const std::string payload = "{\"i\":" + std::to_string(i) + "}";
    const uint16_t ch = i % 3 == 0 ? c0 : i % 3 == 1 ? c1 : c2;
    const uint64_t t = 1000000000ull + static_cast<uint64_t>((i * 7919) % 600) * 1000;
    w.write(ch, t, t + 5, payload.data(), payload.size());
  }
  w.close();
  return path;
}

}  // namespace

TEST_CASE("crc32 is zlib's (the check value of CRC-32/ISO-HDLC)") {
  CHECK(crc32("123456789", 9) == 0xCBF43926u);
  CHECK(crc32("6789", 4, crc32("12345", 5)) == 0xCBF43926u);  // continued
}

TEST_CASE("an MCAP file reads back message by message in file order with its channels and schemas") {
  const auto path = write_sample("roundtrip.mcap");
  McapReader r(path);
  int i = 0;
  r.for_each_message([&](const McapChannel& ch, const McapSchema* schema, const McapMessage& m) {
    CHECK(std::string(m.data.begin(), m.data.end()) == "{\"i\":" + std::to_string(i) + "}");
    CHECK(ch.topic == (i % 3 == 0 ? "A" : i % 3 == 1 ? "B" : "lcm_raw/C"));
    CHECK((schema != nullptr) == (i % 3 != 2));
    CHECK(m.sequence == static_cast<uint32_t>(i / 3));
    CHECK(m.log_time == 1000000000ull + static_cast<uint64_t>((i * 7919) % 600) * 1000);
    CHECK(m.publish_time == m.log_time + 5);
    if (i % 3 == 0) CHECK(ch.metadata.at("lcm_channel") == "A");
    ++i;
  });
  CHECK(i == 600);
  std::remove(path.c_str());
}

TEST_CASE("the summary's statistics and chunk indexes describe the data section") {
  const auto path = write_sample("summary.mcap");
  McapReader r(path);
  const std::string bytes = slurp(path);
  REQUIRE(r.has_statistics());
  const auto& s = r.statistics();
  CHECK(s.message_count == 600);
  CHECK(s.schema_count == 1);
  CHECK(s.channel_count == 3);
  CHECK(s.message_start_time == 1000000000ull);
  CHECK(s.message_end_time == 1000000000ull + 599 * 1000);
  CHECK(s.channel_message_counts.at(0) == 200);
  CHECK(s.channel_message_counts.at(2) == 200);
  CHECK(r.summary_channels().size() == 3);
  CHECK(r.summary_schemas().at(1).name == "sextant.a");
  REQUIRE(r.chunk_indexes().size() == s.chunk_count);
  CHECK(s.chunk_count > 3);  // 4 KiB chunks: the messages span several
  uint64_t prev_end = 0;
  for (const auto& ci : r.chunk_indexes()) {
    CHECK(bytes[ci.chunk_start_offset] == '\x06');                         // a Chunk record
    CHECK(le64(bytes, ci.chunk_start_offset + 1) + 9 == ci.chunk_length);  // whose length the index gives
    CHECK(ci.chunk_start_offset >= prev_end);
    prev_end = ci.chunk_start_offset + ci.chunk_length;
    uint64_t index_bytes = 0;
    for (const auto& [channel, at] : ci.message_index_offsets) {
      CHECK(bytes[at] == '\x07');  // a Message Index record for that channel
      CHECK(static_cast<uint8_t>(bytes[at + 9]) == channel);
      index_bytes += 9 + le64(bytes, at + 1);
    }
    CHECK(index_bytes == ci.message_index_length);
    CHECK(ci.compression == "zstd");
    CHECK(ci.message_start_time <= ci.message_end_time);
  }
  std::remove(path.c_str());
}

TEST_CASE("a flipped byte is caught by the CRC of its section, a cut file by its missing magic") {
  const auto path = write_sample("corrupt.mcap");
  const std::string good = slurp(path);
  McapReader r(path);
  const auto& chunk = r.chunk_indexes().front();
  const auto footer_summary_start = le64(good, good.size() - 8 - 20);

  SUBCASE("summary") {
    std::string bad = good;
    bad[footer_summary_start + 20] ^= 0x01;
    dump(path, bad);
    CHECK_THROWS_WITH_AS(McapReader{path}, doctest::Contains("summary CRC mismatch"), std::runtime_error);
  }
  SUBCASE("chunk") {
    std::string bad = good;
    bad[chunk.chunk_start_offset + chunk.chunk_length - 3] ^= 0x01;  // inside the compressed records
    dump(path, bad);
    McapReader reader(path);
    CHECK_THROWS_AS(reader.for_each_message([](auto&, auto*, auto&) {}), std::runtime_error);
  }
  SUBCASE("message index (data section CRC)") {
    std::string bad = good;
    const auto at = chunk.message_index_offsets.begin()->second;
    bad[at + 9 + 2 + 4 + 3] ^= 0x01;  // a timestamp in the first message index
    dump(path, bad);
    McapReader reader(path);
    CHECK_THROWS_WITH_AS(reader.for_each_message([](auto&, auto*, auto&) {}),
                         doctest::Contains("data section CRC mismatch"), std::runtime_error);
  }
  SUBCASE("cut short") {
    dump(path, good.substr(0, good.size() - 100));
    CHECK_THROWS_WITH_AS(McapReader{path}, doctest::Contains("no closing magic"), std::runtime_error);
  }
  SUBCASE("not MCAP") {
    dump(path, std::string(100, 'x'));
    CHECK_THROWS_WITH_AS(McapReader{path}, doctest::Contains("not an MCAP file"), std::runtime_error);
  }
  std::remove(path.c_str());
}
