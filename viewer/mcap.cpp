#include "viewer/mcap.hpp"

#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <array>
#include <memory>
#include <new>
#include <stdexcept>

namespace sextant::viewer {
namespace {

constexpr char kMagic[8] = {'\x89', 'M', 'C', 'A', 'P', '0', '\r', '\n'};
enum Op : uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kStatistics = 0x0B,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};
constexpr size_t kFooterRecordSize = 1 + 8 + 8 + 8 + 4;

// ---- encoding (little-endian) ----
template <class T>
void le(std::string& out, T v) {
  for (size_t i = 0; i < sizeof(T); ++i) out.push_back(static_cast<char>((static_cast<uint64_t>(v) >> (8 * i)) & 0xFF));
}
void str(std::string& out, const std::string& s) {
  le<uint32_t>(out, static_cast<uint32_t>(s.size()));
  out += s;
}
std::string record(uint8_t op, const std::string& content) {
  std::string r;
  r.reserve(9 + content.size());
  r.push_back(static_cast<char>(op));
  le<uint64_t>(r, content.size());
  r += content;
  return r;
}
std::string schema_record(const McapSchema& s) {
  std::string c;
  le<uint16_t>(c, s.id);
  str(c, s.name);
  str(c, s.encoding);
  str(c, s.data);
  return record(kSchema, c);
}
std::string channel_record(const McapChannel& ch) {
  std::string c, map;
  le<uint16_t>(c, ch.id);
  le<uint16_t>(c, ch.schema_id);
  str(c, ch.topic);
  str(c, ch.message_encoding);
  for (const auto& [k, v] : ch.metadata) {
    str(map, k);
    str(map, v);
  }
  str(c, map);
  return record(kChannel, c);
}

// ---- decoding: a cursor over one record's content that names the file offset of what it cannot read ----
/// Reads the fields of one record's content (which must outlive the cursor).
class Cursor {
 public:
  Cursor(const std::string& bytes, uint64_t file_offset, const std::string& path, const char* what)
      : b_(bytes), base_(file_offset), path_(path), what_(what) {}
  template <class T>
  T get() {
    need(sizeof(T));
    uint64_t v = 0;
    for (size_t i = 0; i < sizeof(T); ++i) v |= static_cast<uint64_t>(static_cast<uint8_t>(b_[pos_ + i])) << (8 * i);
    pos_ += sizeof(T);
    return static_cast<T>(v);
  }
  std::string bytes(uint64_t n) {
    need(n);
    std::string s = b_.substr(pos_, n);
    pos_ += n;
    return s;
  }
  std::string string() { return bytes(get<uint32_t>()); }
  std::map<std::string, std::string> string_map() {
    const uint64_t at = base_ + pos_;
    const std::string entries = bytes(get<uint32_t>());
    Cursor m(entries, at, path_, what_);
    std::map<std::string, std::string> out;
    while (!m.done()) {
      auto k = m.string();
      out[k] = m.string();
    }
    return out;
  }
  bool done() const { return pos_ >= b_.size(); }
  size_t pos() const { return pos_; }
  [[noreturn]] void fail(const std::string& why) const {
    throw std::runtime_error(path_ + ": byte " + std::to_string(base_ + pos_) + ": " + what_ + ": " + why);
  }

 private:
  void need(uint64_t n) const {
    if (n > b_.size() - pos_)
      fail("needs " + std::to_string(n) + " bytes, " + std::to_string(b_.size() - pos_) + " left in the record");
  }
  const std::string& b_;
  size_t pos_ = 0;
  uint64_t base_;
  const std::string& path_;
  const char* what_;
};

McapSchema parse_schema(Cursor c) {
  McapSchema s;
  s.id = c.get<uint16_t>();
  s.name = c.string();
  s.encoding = c.string();
  s.data = c.string();
  return s;
}
McapChannel parse_channel(Cursor c) {
  McapChannel ch;
  ch.id = c.get<uint16_t>();
  ch.schema_id = c.get<uint16_t>();
  ch.topic = c.string();
  ch.message_encoding = c.string();
  ch.metadata = c.string_map();
  return ch;
}

}  // namespace

uint32_t crc32(const void* data, size_t size, uint32_t crc) {
  // zlib's, in pieces that fit its uInt lengths (several GB/s where the table-driven loop ran at a few hundred MB/s).
  const auto* p = static_cast<const Bytef*>(data);
  uLong c = crc;
  while (size > 0) {
    const auto n = static_cast<uInt>(std::min<size_t>(size, 1u << 30));
    c = ::crc32(c, p, n);
    p += n;
    size -= n;
  }
  return static_cast<uint32_t>(c);
}

// ================================ writer ================================

McapWriter::McapWriter(const std::string& path, McapWriterOptions options)
    : path_(path), options_(std::move(options)), out_(path, std::ios::binary | std::ios::trunc) {
  if (!out_) throw std::runtime_error("cannot write " + path);
  put(std::string(kMagic, 8));
  std::string h;
  str(h, options_.profile);
  str(h, options_.library);
  put(record(kHeader, h));
}

McapWriter::~McapWriter() {
  if (!closed_) {
    try {
      close();
    } catch (...) {  // a destructor must not throw; close() reports the error to a caller that asks
    }
  }
}

void McapWriter::put(const std::string& bytes) {
  if (!in_summary_) data_crc_ = crc32(bytes.data(), bytes.size(), data_crc_);
  out_.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out_) throw std::runtime_error("cannot write " + path_ + " (disk full?)");
  offset_ += bytes.size();
}

uint16_t McapWriter::add_schema(const std::string& name, const std::string& encoding, const std::string& data) {
  if (schemas_.size() >= 0xFFFE) throw std::runtime_error(path_ + ": too many schemas for one MCAP file");
  schemas_.push_back({static_cast<uint16_t>(schemas_.size() + 1), name, encoding, data});
  schema_in_chunk_.push_back(false);
  return schemas_.back().id;
}

uint16_t McapWriter::add_channel(uint16_t schema_id, const std::string& topic, const std::string& message_encoding,
                                 const std::map<std::string, std::string>& metadata) {
  if (schema_id > schemas_.size()) throw std::runtime_error(path_ + ": channel " + topic + " names an unknown schema");
  if (channels_.size() >= 0xFFFF) throw std::runtime_error(path_ + ": too many channels for one MCAP file");
  channels_.push_back({static_cast<uint16_t>(channels_.size()), schema_id, topic, message_encoding, metadata});
  sequence_.push_back(0);
  in_chunk_.push_back(false);
  return channels_.back().id;
}

void McapWriter::write(uint16_t channel_id, uint64_t log_time, uint64_t publish_time, const void* data, size_t size) {
  if (closed_) throw std::runtime_error(path_ + ": write after close");
  if (channel_id >= channels_.size()) throw std::runtime_error(path_ + ": message on an unknown channel");
  const auto& ch = channels_[channel_id];
  // A chunk is self-contained: the schema and channel of each of its messages come before the first one in it.
  if (ch.schema_id != 0 && !schema_in_chunk_[ch.schema_id - 1]) {
    chunk_ += schema_record(schemas_[ch.schema_id - 1]);
    schema_in_chunk_[ch.schema_id - 1] = true;
  }
  if (!in_chunk_[channel_id]) {
    chunk_ += channel_record(ch);
    in_chunk_[channel_id] = true;
  }
  chunk_index_[channel_id].emplace_back(log_time, chunk_.size());
  std::string c;
  c.reserve(22 + size);
  le<uint16_t>(c, channel_id);
  le<uint32_t>(c, sequence_[channel_id]++);
  le<uint64_t>(c, log_time);
  le<uint64_t>(c, publish_time);
  c.append(static_cast<const char*>(data), size);
  chunk_ += record(kMessage, c);

  chunk_start_ = chunk_has_messages_ ? std::min(chunk_start_, log_time) : log_time;
  chunk_end_ = chunk_has_messages_ ? std::max(chunk_end_, log_time) : log_time;
  chunk_has_messages_ = true;
  stats_.message_start_time = stats_.message_count ? std::min(stats_.message_start_time, log_time) : log_time;
  stats_.message_end_time = stats_.message_count ? std::max(stats_.message_end_time, log_time) : log_time;
  ++stats_.message_count;
  ++stats_.channel_message_counts[channel_id];
  if (chunk_.size() >= options_.chunk_size) flush_chunk();
}

// Step 1 of closing a chunk: compress and write it, its message indexes after it, and remember its chunk index.
void McapWriter::flush_chunk() {
  if (chunk_.empty()) return;
  std::string compressed(ZSTD_compressBound(chunk_.size()), '\0');
  const size_t n =
      ZSTD_compress(compressed.data(), compressed.size(), chunk_.data(), chunk_.size(), options_.zstd_level);
  if (ZSTD_isError(n)) throw std::runtime_error(path_ + ": zstd: " + ZSTD_getErrorName(n));
  compressed.resize(n);

  std::string c;
  le<uint64_t>(c, chunk_start_);
  le<uint64_t>(c, chunk_end_);
  le<uint64_t>(c, chunk_.size());
  le<uint32_t>(c, crc32(chunk_.data(), chunk_.size()));
  str(c, "zstd");
  le<uint64_t>(c, compressed.size());
  c += compressed;

  McapChunkIndex index;
  index.message_start_time = chunk_start_;
  index.message_end_time = chunk_end_;
  index.chunk_start_offset = offset_;
  index.compression = "zstd";
  index.compressed_size = compressed.size();
  index.uncompressed_size = chunk_.size();
  put(record(kChunk, c));
  index.chunk_length = offset_ - index.chunk_start_offset;

  const uint64_t indexes_start = offset_;
  for (auto& [channel, entries] : chunk_index_) {
    std::stable_sort(entries.begin(), entries.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    std::string m, list;
    le<uint16_t>(m, channel);
    for (const auto& [time, at] : entries) {
      le<uint64_t>(list, time);
      le<uint64_t>(list, at);
    }
    str(m, list);
    index.message_index_offsets[channel] = offset_;
    put(record(kMessageIndex, m));
  }
  index.message_index_length = offset_ - indexes_start;
  chunk_indexes_.push_back(std::move(index));
  ++stats_.chunk_count;

  chunk_.clear();
  chunk_index_.clear();
  chunk_has_messages_ = false;
  std::fill(in_chunk_.begin(), in_chunk_.end(), false);
  std::fill(schema_in_chunk_.begin(), schema_in_chunk_.end(), false);
}

void McapWriter::close() {
  if (closed_) return;
  closed_ = true;
  flush_chunk();
  write_summary();
  out_.flush();
  if (!out_) throw std::runtime_error("cannot write " + path_ + " (disk full?)");
  out_.close();
}

// Step 2 of closing: Data End, the summary groups with their offsets, the Footer and the closing magic.
void McapWriter::write_summary() {
  std::string end;
  le<uint32_t>(end, data_crc_);
  put(record(kDataEnd, end));
  in_summary_ = true;

  const uint64_t summary_start = offset_;
  std::string summary, offsets;
  auto group = [&](uint8_t op, const std::string& records) {
    if (records.empty()) return;
    std::string o;
    le<uint8_t>(o, op);
    le<uint64_t>(o, summary_start + summary.size());
    le<uint64_t>(o, records.size());
    offsets += record(kSummaryOffset, o);
    summary += records;
  };
  std::string schemas, channels, chunk_indexes, statistics;
  for (const auto& s : schemas_) schemas += schema_record(s);
  for (const auto& ch : channels_) channels += channel_record(ch);
  for (const auto& ci : chunk_indexes_) {
    std::string c, map;
    le<uint64_t>(c, ci.message_start_time);
    le<uint64_t>(c, ci.message_end_time);
    le<uint64_t>(c, ci.chunk_start_offset);
    le<uint64_t>(c, ci.chunk_length);
    for (const auto& [channel, at] : ci.message_index_offsets) {
      le<uint16_t>(map, channel);
      le<uint64_t>(map, at);
    }
    str(c, map);
    le<uint64_t>(c, ci.message_index_length);
    str(c, ci.compression);
    le<uint64_t>(c, ci.compressed_size);
    le<uint64_t>(c, ci.uncompressed_size);
    chunk_indexes += record(kChunkIndex, c);
  }
  stats_.schema_count = static_cast<uint16_t>(schemas_.size());
  stats_.channel_count = static_cast<uint32_t>(channels_.size());
  {
    std::string c, map;
    le<uint64_t>(c, stats_.message_count);
    le<uint16_t>(c, stats_.schema_count);
    le<uint32_t>(c, stats_.channel_count);
    le<uint32_t>(c, 0);  // attachments
    le<uint32_t>(c, 0);  // metadata records
    le<uint32_t>(c, stats_.chunk_count);
    le<uint64_t>(c, stats_.message_start_time);
    le<uint64_t>(c, stats_.message_end_time);
    for (const auto& [channel, n] : stats_.channel_message_counts) {
      le<uint16_t>(map, channel);
      le<uint64_t>(map, n);
    }
    str(c, map);
    statistics = record(kStatistics, c);
  }
  group(kSchema, schemas);
  group(kChannel, channels);
  group(kStatistics, statistics);
  group(kChunkIndex, chunk_indexes);

  const uint64_t offsets_start = summary_start + summary.size();
  std::string footer;
  footer.push_back(static_cast<char>(kFooter));
  le<uint64_t>(footer, 8 + 8 + 4);
  le<uint64_t>(footer, summary.empty() ? 0 : summary_start);
  le<uint64_t>(footer, offsets.empty() ? 0 : offsets_start);
  std::string covered = summary + offsets + footer;
  le<uint32_t>(footer, crc32(covered.data(), covered.size()));
  put(summary);
  put(offsets);
  put(footer);
  put(std::string(kMagic, 8));
}

}  // namespace sextant::viewer

// ================================ reader ================================
namespace sextant::viewer {
namespace {

struct RawRecord {
  uint8_t op = 0;
  uint64_t offset = 0;  // of the opcode, in the file (or in the chunk's records)
  std::string content;
};

/// The records of a chunk's uncompressed bytes, one after another.
std::vector<RawRecord> split_records(const std::string& bytes, uint64_t base, const std::string& path) {
  std::vector<RawRecord> out;
  size_t pos = 0;
  while (pos < bytes.size()) {
    if (bytes.size() - pos < 9)
      throw std::runtime_error(path + ": byte " + std::to_string(base + pos) + ": record header cut short in a chunk");
    RawRecord r;
    r.op = static_cast<uint8_t>(bytes[pos]);
    r.offset = pos;
    uint64_t len = 0;
    for (int i = 0; i < 8; ++i) len |= static_cast<uint64_t>(static_cast<uint8_t>(bytes[pos + 1 + i])) << (8 * i);
    if (len > bytes.size() - pos - 9)
      throw std::runtime_error(path + ": chunk at byte " + std::to_string(base) + ": record at " + std::to_string(pos) +
                               " claims " + std::to_string(len) + " bytes past the chunk's end");
    r.content = bytes.substr(pos + 9, len);
    pos += 9 + len;
    out.push_back(std::move(r));
  }
  return out;
}

// A chunk's records from its bytes.  The output grows as zstd produces it, up to one byte past what the chunk's
// header claims: a small chunk that claims gigabytes costs what it really holds, not what it claims.
std::string decompress(const std::string& compression, const std::string& data, uint64_t size,
                       const std::string& where) {
  if (compression.empty()) return data;
  if (compression != "zstd")
    throw std::runtime_error(where + ": chunk compression '" + compression + "' is not supported (zstd or none)");
  if (size > (uint64_t{1} << 34))
    throw std::runtime_error(where + ": chunk claims " + std::to_string(size) + " bytes uncompressed");
  const std::unique_ptr<ZSTD_DCtx, size_t (*)(ZSTD_DCtx*)> ctx(ZSTD_createDCtx(), ZSTD_freeDCtx);
  if (!ctx) throw std::bad_alloc();
  std::string out(std::min<uint64_t>(size + 1, uint64_t{1} << 20), '\0');
  ZSTD_inBuffer in{data.data(), data.size(), 0};
  size_t produced = 0;
  for (size_t left = 1; left != 0 || in.pos < in.size;) {  // left: 0 once a frame is done (more may follow)
    if (produced == out.size()) {
      if (out.size() > size) break;  // more than claimed
      out.resize(std::min<uint64_t>(size + 1, 2 * out.size()));
    }
    ZSTD_outBuffer o{out.data(), out.size(), produced};
    const size_t before = in.pos;
    left = ZSTD_decompressStream(ctx.get(), &o, &in);
    if (ZSTD_isError(left)) throw std::runtime_error(where + ": zstd: " + ZSTD_getErrorName(left));
    if (left != 0 && in.pos == in.size && in.pos == before && o.pos == produced)
      throw std::runtime_error(where + ": zstd: the compressed data ends inside a frame");
    produced = o.pos;
  }
  if (produced != size)
    throw std::runtime_error(where + ": chunk decompressed to " + (produced > size ? "more than " : "") +
                             std::to_string(produced) + " bytes, its header says " + std::to_string(size));
  out.resize(produced);
  return out;
}

}  // namespace

McapReader::McapReader(const std::string& path) : path_(path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) throw std::runtime_error("cannot read " + path);
  size_ = static_cast<uint64_t>(in.tellg());
  if (size_ < 8 + 9 + 8 + kFooterRecordSize + 8)
    throw std::runtime_error(path + ": too small to be an MCAP file (" + std::to_string(size_) + " bytes)");
  if (read_at(0, 8) != std::string(kMagic, 8)) throw std::runtime_error(path + ": byte 0: not an MCAP file (no magic)");
  if (read_at(size_ - 8, 8) != std::string(kMagic, 8))
    throw std::runtime_error(path + ": byte " + std::to_string(size_ - 8) + ": no closing magic (file cut short?)");
  const std::string header = read_at(8, 9);
  if (header[0] != static_cast<char>(kHeader))
    throw std::runtime_error(path + ": byte 8: the first record is not a Header");
  Cursor hc(header, 8, path, "Header");
  hc.get<uint8_t>();
  const uint64_t hlen = hc.get<uint64_t>();
  if (hlen > size_ - 17) throw std::runtime_error(path + ": byte 9: Header length past the end of the file");
  const std::string hcontent = read_at(17, hlen);
  Cursor h(hcontent, 17, path, "Header");
  profile_ = h.string();
  read_summary();
}

std::string McapReader::read_at(uint64_t offset, uint64_t size) const {
  if (offset > size_ || size > size_ - offset)
    throw std::runtime_error(path_ + ": byte " + std::to_string(offset) + ": " + std::to_string(size) +
                             " bytes past the end of the file");
  std::ifstream in(path_, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(offset));
  std::string out(size, '\0');
  in.read(out.data(), static_cast<std::streamsize>(size));
  if (!in)
    throw std::runtime_error(path_ + ": cannot read " + std::to_string(size) + " bytes at " + std::to_string(offset));
  return out;
}

// The Footer, then (when there is one) the summary section with its CRC checked.
void McapReader::read_summary() {
  const uint64_t footer_at = size_ - 8 - kFooterRecordSize;
  const std::string footer = read_at(footer_at, kFooterRecordSize);
  Cursor f(footer, footer_at, path_, "Footer");
  if (f.get<uint8_t>() != kFooter || f.get<uint64_t>() != 20) f.fail("not a Footer record");
  const uint64_t summary_start = f.get<uint64_t>();
  const uint64_t offsets_start = f.get<uint64_t>();
  const uint32_t summary_crc = f.get<uint32_t>();
  if (summary_start == 0) return;
  if (summary_start > footer_at || (offsets_start != 0 && (offsets_start < summary_start || offsets_start > footer_at)))
    f.fail("summary offsets outside the file");
  const std::string summary = read_at(summary_start, footer_at - summary_start);
  if (summary_crc != 0) {
    uint32_t crc = crc32(summary.data(), summary.size());
    crc = crc32(footer.data(), kFooterRecordSize - 4, crc);
    if (crc != summary_crc) throw std::runtime_error(path_ + ": summary CRC mismatch (the summary section is corrupt)");
  }
  const uint64_t records_end = (offsets_start ? offsets_start : footer_at) - summary_start;
  size_t pos = 0;
  while (pos < records_end) {
    Cursor head(summary, summary_start, path_, "summary record");
    if (records_end - pos < 9) head.fail("record header cut short");
    const uint8_t op = static_cast<uint8_t>(summary[pos]);
    uint64_t len = 0;
    for (int i = 0; i < 8; ++i) len |= static_cast<uint64_t>(static_cast<uint8_t>(summary[pos + 1 + i])) << (8 * i);
    if (len > records_end - pos - 9)
      throw std::runtime_error(path_ + ": byte " + std::to_string(summary_start + pos) +
                               ": summary record past the summary's end");
    const std::string content = summary.substr(pos + 9, len);
    const uint64_t at = summary_start + pos + 9;
    if (op == kSchema) {
      auto s = parse_schema(Cursor(content, at, path_, "Schema"));
      summary_schemas_[s.id] = s;
    } else if (op == kChannel) {
      auto ch = parse_channel(Cursor(content, at, path_, "Channel"));
      summary_channels_[ch.id] = ch;
    } else if (op == kStatistics) {
      Cursor c(content, at, path_, "Statistics");
      statistics_.message_count = c.get<uint64_t>();
      statistics_.schema_count = c.get<uint16_t>();
      statistics_.channel_count = c.get<uint32_t>();
      c.get<uint32_t>();
      c.get<uint32_t>();
      statistics_.chunk_count = c.get<uint32_t>();
      statistics_.message_start_time = c.get<uint64_t>();
      statistics_.message_end_time = c.get<uint64_t>();
      const std::string counts = c.bytes(c.get<uint32_t>());
      Cursor m(counts, at, path_, "Statistics.channel_message_counts");
      while (!m.done()) {
        const auto ch = m.get<uint16_t>();
        statistics_.channel_message_counts[ch] = m.get<uint64_t>();
      }
      has_statistics_ = true;
    } else if (op == kChunkIndex) {
      Cursor c(content, at, path_, "Chunk Index");
      McapChunkIndex ci;
      ci.message_start_time = c.get<uint64_t>();
      ci.message_end_time = c.get<uint64_t>();
      ci.chunk_start_offset = c.get<uint64_t>();
      ci.chunk_length = c.get<uint64_t>();
      const std::string offsets = c.bytes(c.get<uint32_t>());
      Cursor m(offsets, at, path_, "Chunk Index.message_index_offsets");
      while (!m.done()) {
        const auto ch = m.get<uint16_t>();
        ci.message_index_offsets[ch] = m.get<uint64_t>();
      }
      ci.message_index_length = c.get<uint64_t>();
      ci.compression = c.string();
      ci.compressed_size = c.get<uint64_t>();
      ci.uncompressed_size = c.get<uint64_t>();
      chunk_indexes_.push_back(std::move(ci));
    }
    pos += 9 + len;
  }
}

// A linear scan of the data section: records outside chunks and inside them, in file order.
void McapReader::for_each_message(
    const std::function<void(const McapChannel&, const McapSchema*, const McapMessage&)>& f) {
  std::ifstream in(path_, std::ios::binary);
  uint64_t pos = 0;
  uint32_t data_crc = 0;
  auto read = [&](uint64_t n) {
    if (n > size_ - pos)
      throw std::runtime_error(path_ + ": byte " + std::to_string(pos) + ": record past the end of the file");
    std::string b(n, '\0');
    in.seekg(static_cast<std::streamoff>(pos));
    in.read(b.data(), static_cast<std::streamsize>(n));
    if (!in) throw std::runtime_error(path_ + ": cannot read at byte " + std::to_string(pos));
    pos += n;
    return b;
  };
  data_crc = crc32(read(8).data(), 8);
  std::map<uint16_t, McapSchema> schemas;
  std::map<uint16_t, McapChannel> channels;
  auto handle = [&](uint8_t op, const std::string& content, uint64_t at, const std::string& where) {
    if (op == kSchema) {
      auto s = parse_schema(Cursor(content, at, path_, "Schema"));
      schemas[s.id] = s;
    } else if (op == kChannel) {
      auto ch = parse_channel(Cursor(content, at, path_, "Channel"));
      if (ch.schema_id != 0 && !schemas.count(ch.schema_id))
        throw std::runtime_error(where + ": channel " + ch.topic + " names schema " + std::to_string(ch.schema_id) +
                                 " before it is declared");
      channels[ch.id] = ch;
    } else if (op == kMessage) {
      Cursor c(content, at, path_, "Message");
      McapMessage m;
      m.channel_id = c.get<uint16_t>();
      m.sequence = c.get<uint32_t>();
      m.log_time = c.get<uint64_t>();
      m.publish_time = c.get<uint64_t>();
      m.data.assign(content.begin() + 22, content.end());
      const auto ch = channels.find(m.channel_id);
      if (ch == channels.end())
        throw std::runtime_error(where + ": message on channel " + std::to_string(m.channel_id) +
                                 " before the channel is declared");
      const auto s = schemas.find(ch->second.schema_id);
      f(ch->second, s == schemas.end() ? nullptr : &s->second, m);
    }
  };
  while (true) {
    const uint64_t at = pos;
    const std::string head = read(9);
    const uint8_t op = static_cast<uint8_t>(head[0]);
    uint64_t len = 0;
    for (int i = 0; i < 8; ++i) len |= static_cast<uint64_t>(static_cast<uint8_t>(head[1 + i])) << (8 * i);
    const std::string content = read(len);
    const std::string where = path_ + ": byte " + std::to_string(at);
    if (op == kDataEnd) {
      Cursor c(content, at + 9, path_, "Data End");
      const uint32_t expected = c.get<uint32_t>();
      if (expected != 0 && expected != data_crc)
        throw std::runtime_error(where + ": data section CRC mismatch (the data section is corrupt)");
      return;
    }
    if (op == kFooter) return;  // a file without Data End (older writers)
    data_crc = crc32(head.data(), head.size(), data_crc);
    data_crc = crc32(content.data(), content.size(), data_crc);
    if (op == kChunk) {
      Cursor c(content, at + 9, path_, "Chunk");
      c.get<uint64_t>();
      c.get<uint64_t>();
      const uint64_t uncompressed_size = c.get<uint64_t>();
      const uint32_t uncompressed_crc = c.get<uint32_t>();
      const std::string compression = c.string();
      const std::string records = decompress(compression, c.bytes(c.get<uint64_t>()), uncompressed_size, where);
      if (uncompressed_crc != 0 && crc32(records.data(), records.size()) != uncompressed_crc)
        throw std::runtime_error(where + ": chunk CRC mismatch (the chunk is corrupt)");
      for (const auto& r : split_records(records, at, path_))
        handle(r.op, r.content, at, where + " (chunk), record at " + std::to_string(r.offset));
    } else {
      handle(op, content, at + 9, where);
    }
  }
}

}  // namespace sextant::viewer
