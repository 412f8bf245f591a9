#include "viewer/lcm_mcap.hpp"

#include "daemon/runtime/lcm_log.hpp"
#include "daemon/runtime/version.hpp"
#include "replay/time_ordered_log.hpp"

#include <algorithm>
#include <filesystem>
#include <limits>
#include <stdexcept>

namespace sextant::viewer {
namespace {

McapWriterOptions with_library(McapWriterOptions o) {
  if (o.library.empty()) o.library = std::string("sextant ") + sextant::version();
  return o;
}

/// The utime of a sextant message in ns (tools::peek_utime); `fallback` for other bytes or a negative utime.
uint64_t publish_time(const uint8_t* data, size_t size, uint64_t fallback) {
  if (!lcm_json_type_of(data, size)) return fallback;
  const auto us = tools::peek_utime(std::vector<uint8_t>(data, data + std::min<size_t>(size, 16)));
  return us && *us >= 0 ? static_cast<uint64_t>(*us) * 1000 : fallback;
}

}  // namespace

McapRecorder::McapRecorder(const std::string& path, McapWriterOptions options)
    : writer_(path, with_library(std::move(options))), mapper_(TopicMapperOptions{true, true}) {}

uint16_t McapRecorder::channel_for(const ViewerMessage& m) {
  const std::string kind = m.schema ? m.schema->name : m.encoding;
  const auto key = std::make_pair(m.topic, kind);
  if (const auto it = channel_ids_.find(key); it != channel_ids_.end()) return it->second;
  uint16_t schema_id = 0;
  if (m.schema) {
    auto s = schema_ids_.find(m.schema->name);
    if (s == schema_ids_.end())
      s = schema_ids_.emplace(m.schema->name, writer_.add_schema(m.schema->name, m.schema->encoding, m.schema->data))
              .first;
    schema_id = s->second;
  }
  std::map<std::string, std::string> metadata;
  if (!m.lcm_channel.empty()) metadata["lcm_channel"] = m.lcm_channel;
  const uint16_t id = writer_.add_channel(schema_id, m.topic, m.encoding, metadata);
  channel_ids_.emplace(key, id);
  return id;
}

void McapRecorder::add(const std::string& channel, int64_t timestamp_us, const uint8_t* data, size_t size) {
  scratch_.clear();
  mapper_.map(channel, data, size, scratch_);
  const auto log_time = static_cast<uint64_t>(timestamp_us) * 1000;
  const uint64_t published = publish_time(data, size, log_time);
  for (const auto& m : scratch_) writer_.write(channel_for(m), log_time, published, m.data.data(), m.data.size());
}

void McapRecorder::close() { writer_.close(); }

ReplayMcapRecorder::ReplayMcapRecorder(const std::string& log_path, const std::string& mcap_path)
    : inputs_(log_path), next_input_(inputs_.next()), recorder_(mcap_path) {}

void ReplayMcapRecorder::inputs_until(int64_t utime) {
  while (next_input_) {
    const int64_t t = tools::replay_stamp(*next_input_);
    if (t > utime) return;
    recorder_.add(next_input_->channel, t, next_input_->data.data(), next_input_->data.size());
    next_input_ = inputs_.next();
  }
}

void ReplayMcapRecorder::published(const std::string& channel, const std::vector<uint8_t>& bytes, int64_t utime) {
  inputs_until(utime);
  recorder_.add(channel, utime, bytes.data(), bytes.size());
}

void ReplayMcapRecorder::close() {
  inputs_until(std::numeric_limits<int64_t>::max());
  recorder_.close();
}

LcmToMcapResult convert_lcm_to_mcap(const std::string& lcm_path, const std::string& mcap_path,
                                    McapWriterOptions options) {
  runtime::LogReader reader(lcm_path);
  McapRecorder recorder(mcap_path, std::move(options));
  LcmToMcapResult r;
  while (auto e = reader.next()) {
    recorder.add(e->channel, e->timestamp, e->data.data(), e->data.size());
    ++r.events;
  }
  recorder.close();
  r.raw = recorder.mapper_counts().raw;
  r.log_damage = reader.damage().summary();
  r.statistics = recorder.statistics();
  r.bytes_in = std::filesystem::file_size(lcm_path);
  r.bytes_out = recorder.bytes_written();
  return r;
}

McapToLcmResult convert_mcap_to_lcm(const std::string& mcap_path, const std::string& lcm_path) {
  McapReader reader(mcap_path);
  runtime::LogWriter writer(lcm_path);
  McapToLcmResult r;
  int64_t index = 0;
  reader.for_each_message([&](const McapChannel& ch, const McapSchema* schema, const McapMessage& m) {
    ++index;
    const auto lcm = ch.metadata.find("lcm_channel");
    if (lcm == ch.metadata.end()) {
      ++r.views_skipped;
      return;
    }
    const int64_t timestamp = static_cast<int64_t>(m.log_time) / 1000;  // the two's-complement bits of a negative one
    const std::string where = mcap_path + ": message " + std::to_string(index) + " on topic " + ch.topic;
    if (ch.message_encoding == "lcm") {
      writer.write_raw(timestamp, lcm->second, m.data.data(), m.data.size());
    } else if (ch.message_encoding == "json") {
      const LcmJsonType* type = schema ? lcm_json_type_named(schema->name) : nullptr;
      if (!type)
        throw std::runtime_error(where + ": schema " + (schema ? schema->name : "(none)") + " is not a sextant type");
      std::vector<uint8_t> bytes;
      try {
        bytes = type->encode(Json::parse(m.data.begin(), m.data.end()));
      } catch (const std::exception& e) {
        throw std::runtime_error(where + ": " + e.what());
      }
      writer.write_raw(timestamp, lcm->second, bytes.data(), bytes.size());
    } else {
      throw std::runtime_error(where + ": message encoding '" + ch.message_encoding + "' is neither json nor lcm");
    }
    ++r.events;
  });
  writer.flush();
  return r;
}

}  // namespace sextant::viewer
