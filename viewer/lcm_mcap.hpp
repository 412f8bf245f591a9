#pragma once
// LCM logs <-> MCAP files.  LCM -> MCAP writes every event through the viewer mapping (topics.hpp): each sextant
// channel as-is (JSON with its generated schema, channel metadata "lcm_channel" naming the LCM channel) plus the
// Foxglove views, chunked and zstd-compressed with a full summary (mcap.hpp).  An event's LCM timestamp (us) becomes
// the MCAP log_time (ns; a negative timestamp keeps its two's-complement bits), its message's utime the
// publish_time.  MCAP -> LCM reads back the channels that carry "lcm_channel" (views are skipped): the JSON
// re-encoded by the generated conversions, raw LCM bytes as they are, each with its log_time as the LCM timestamp,
// in file order.  The round trip gives the same channels, timestamps and bytes in the same order.
#include "daemon/runtime/lcm_log.hpp"
#include "viewer/mcap.hpp"
#include "viewer/topics.hpp"

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace sextant::viewer {

/// Writes LCM events as an MCAP file through the viewer mapping, registering each topic's schema and channel on its
/// first message.
class McapRecorder {
 public:
  explicit McapRecorder(const std::string& path, McapWriterOptions options = {});
  /// One LCM event: `channel`, its timestamp in microseconds and its encoded bytes.
  void add(const std::string& channel, int64_t timestamp_us, const uint8_t* data, size_t size);
  /// Writes the summary; throws on I/O errors.
  void close();
  const McapStatistics& statistics() const { return writer_.statistics(); }
  const TopicMapperCounts& mapper_counts() const { return mapper_.counts(); }
  uint64_t bytes_written() const { return writer_.bytes_written(); }

 private:
  uint16_t channel_for(const ViewerMessage& m);

  McapWriter writer_;
  TopicMapper mapper_;
  std::map<std::string, uint16_t> schema_ids_;                           // by schema name
  std::map<std::pair<std::string, std::string>, uint16_t> channel_ids_;  // by (topic, schema name or encoding)
  std::vector<ViewerMessage> scratch_;
};

/// `sextant replay LOG --mcap-out F`: what the replay read and what it published, in one file.  Each published
/// message is written when the replay publishes it, after the log's inputs up to its utime (read in file order from
/// a second reader, so memory stays bounded); the inputs left are written at close().  Every message's log_time is
/// its utime (data time), so inputs and outputs line up in a viewer whatever clock stamped the log.
class ReplayMcapRecorder {
 public:
  ReplayMcapRecorder(const std::string& log_path, const std::string& mcap_path);
  void published(const std::string& channel, const std::vector<uint8_t>& bytes, int64_t utime);
  void close();

 private:
  void inputs_until(int64_t utime);

  runtime::LogReader inputs_;
  std::optional<runtime::LogRecord> next_input_;
  McapRecorder recorder_;
};

struct LcmToMcapResult {
  int64_t events = 0;         // LCM events read
  int64_t raw = 0;            // of them, kept as raw LCM bytes (no JSON form)
  std::string log_damage;     // what the LCM reader skipped ("" when the log is clean)
  McapStatistics statistics;  // of the MCAP file written
  uint64_t bytes_in = 0, bytes_out = 0;
};
/// `sextant convert mcap IN.lcm -o OUT.mcap`.  Throws std::runtime_error naming the file on errors.
LcmToMcapResult convert_lcm_to_mcap(const std::string& lcm_path, const std::string& mcap_path,
                                    McapWriterOptions options = {});

struct McapToLcmResult {
  int64_t events = 0;         // LCM events written
  int64_t views_skipped = 0;  // MCAP messages of the Foxglove views (not LCM channels)
};
/// `sextant convert lcm IN.mcap -o OUT.lcm`.  Throws std::runtime_error naming the file, message and field on errors.
McapToLcmResult convert_mcap_to_lcm(const std::string& mcap_path, const std::string& lcm_path);

}  // namespace sextant::viewer
