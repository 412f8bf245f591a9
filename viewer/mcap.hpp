#pragma once
// MCAP files (https://mcap.dev/spec, format version 0): a writer and a reader of the records sextant uses.
//
// Layout written:  magic | Header | data section | Data End | summary section | summary offsets | Footer | magic
//   data section:  Chunk records (zstd-compressed; each holds the Schema and Channel records of its channels before
//                  their first message in it, then Message records), each followed by one Message Index per channel
//   summary:       every Schema, every Channel, one Statistics, one Chunk Index per chunk, and a Summary Offset per
//                  group, so a reader seeks to any time without scanning the data section.
// CRCs: each chunk's uncompressed records, the data section (from the first magic byte to the Data End record) and
// the summary (from its start through the Footer's summary_offset_start).  Integers little-endian; a string is a
// uint32 length and its bytes; a map or array is a uint32 byte length and its entries.
// No maintained C++ MCAP library is packaged by Debian; tests/viewer/ checks these files with the reference reader
// (@mcap/core's indexed reader).
#include <cstddef>
#include <cstdint>
#include <fstream>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace sextant::viewer {

/// CRC-32 (ISO-HDLC, zlib's: reflected polynomial 0xEDB88320), continued from `crc` (0 to start), computed by zlib.
uint32_t crc32(const void* data, size_t size, uint32_t crc = 0);

struct McapSchema {
  uint16_t id = 0;       // > 0
  std::string name;      // "foxglove.PoseInFrame"
  std::string encoding;  // "jsonschema"
  std::string data;      // the schema text
};

struct McapChannel {
  uint16_t id = 0;
  uint16_t schema_id = 0;  // 0: no schema
  std::string topic;
  std::string message_encoding;  // "json"
  std::map<std::string, std::string> metadata;
};

struct McapMessage {
  uint16_t channel_id = 0;
  uint32_t sequence = 0;
  uint64_t log_time = 0;      // nanoseconds
  uint64_t publish_time = 0;  // nanoseconds
  std::vector<uint8_t> data;
};

struct McapStatistics {
  uint64_t message_count = 0;
  uint16_t schema_count = 0;
  uint32_t channel_count = 0, chunk_count = 0;
  uint64_t message_start_time = 0, message_end_time = 0;
  std::map<uint16_t, uint64_t> channel_message_counts;
};

struct McapChunkIndex {
  uint64_t message_start_time = 0, message_end_time = 0;
  uint64_t chunk_start_offset = 0, chunk_length = 0;
  std::map<uint16_t, uint64_t> message_index_offsets;  // channel -> file offset of its Message Index record
  uint64_t message_index_length = 0;
  std::string compression;
  uint64_t compressed_size = 0, uncompressed_size = 0;
};

struct McapWriterOptions {
  size_t chunk_size = 1 << 20;  // uncompressed bytes of records after which a chunk is closed
  int zstd_level = 3;           // zstd's default: ~3x on sextant's JSON at several hundred MB/s
  std::string profile;          // "" : no well-known profile (JSON messages with JSON Schemas)
  std::string library;          // written into the Header ("sextant 0.1.0")
};

/// Writes an MCAP file.  Schemas and channels are declared first, then messages in any order (a reader orders them
/// by log_time through the indexes).  close() writes the summary; the destructor closes when close() was not called
/// (and swallows errors: call close() to see them).  Throws std::runtime_error naming the path on I/O errors.
class McapWriter {
 public:
  McapWriter(const std::string& path, McapWriterOptions options = {});
  ~McapWriter();
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  uint16_t add_schema(const std::string& name, const std::string& encoding, const std::string& data);
  uint16_t add_channel(uint16_t schema_id, const std::string& topic, const std::string& message_encoding,
                       const std::map<std::string, std::string>& metadata = {});
  void write(uint16_t channel_id, uint64_t log_time, uint64_t publish_time, const void* data, size_t size);
  void close();

  const McapStatistics& statistics() const { return stats_; }
  uint64_t bytes_written() const { return offset_; }

 private:
  void put(const std::string& bytes);
  void flush_chunk();
  void write_summary();

  std::string path_;
  McapWriterOptions options_;
  std::ofstream out_;
  uint64_t offset_ = 0;
  uint32_t data_crc_ = 0;  // running CRC of everything written before the Data End record
  bool in_summary_ = false;
  bool closed_ = false;
  std::vector<McapSchema> schemas_;
  std::vector<McapChannel> channels_;
  std::vector<uint32_t> sequence_;            // next sequence number per channel id
  std::vector<bool> in_chunk_;                // channel id declared in the open chunk
  std::vector<bool> schema_in_chunk_;         // schema id declared in the open chunk
  std::string chunk_;                         // the open chunk's uncompressed records
  uint64_t chunk_start_ = 0, chunk_end_ = 0;  // message time range of the open chunk
  bool chunk_has_messages_ = false;
  std::map<uint16_t, std::vector<std::pair<uint64_t, uint64_t>>> chunk_index_;  // channel -> (log_time, offset)
  std::vector<McapChunkIndex> chunk_indexes_;
  McapStatistics stats_;
};

/// Reads an MCAP file from memory-sized pieces of the file: the footer and summary first, then the data section in
/// file order.  Checks the magic at both ends, every CRC that is not zero (data section, summary, each chunk) and
/// every length; throws std::runtime_error naming the file and byte offset of what is wrong.  Reads chunks
/// compressed with zstd or not at all.
class McapReader {
 public:
  explicit McapReader(const std::string& path);

  /// Every message in file order (the order a writer wrote them), with the schemas and channels it declared
  /// before it.  Checks the data section's CRC once the scan reaches the Data End record.
  void for_each_message(const std::function<void(const McapChannel&, const McapSchema*, const McapMessage&)>& f);

  /// What the summary section holds (empty when the file has none).
  const std::map<uint16_t, McapSchema>& summary_schemas() const { return summary_schemas_; }
  const std::map<uint16_t, McapChannel>& summary_channels() const { return summary_channels_; }
  const std::vector<McapChunkIndex>& chunk_indexes() const { return chunk_indexes_; }
  bool has_statistics() const { return has_statistics_; }
  const McapStatistics& statistics() const { return statistics_; }
  const std::string& profile() const { return profile_; }

 private:
  std::string read_at(uint64_t offset, uint64_t size) const;
  void read_summary();

  std::string path_;
  uint64_t size_ = 0;
  std::string profile_;
  std::map<uint16_t, McapSchema> summary_schemas_;
  std::map<uint16_t, McapChannel> summary_channels_;
  std::vector<McapChunkIndex> chunk_indexes_;
  McapStatistics statistics_;
  bool has_statistics_ = false;
};

}  // namespace sextant::viewer
