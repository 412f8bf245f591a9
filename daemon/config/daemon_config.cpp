#include "daemon/config/daemon_config.hpp"

#include "daemon/config/engine_config_fields.hpp"

#include "daemon/config/stage_config_readers.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

namespace sextant::config {
namespace {

Check<std::string> channel_name() {
  return [](const std::string& v) -> std::optional<std::string> {
    if (v.empty()) return "must not be empty";
    for (char c : v)
      if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.' || c == '/'))
        return "channel names use letters, digits and _ - . / only; got '" + v + "'";
    return std::nullopt;
  };
}

// Channels that cannot work: a name (with the prefix) longer than LCM allows is neither sent nor received; two
// inputs on one channel feed one kind's decoder with the other's messages; an output named like an input comes
// back to the daemon as input.  Each is an error at the key that makes it so.
// The fleet's channels go without the prefix (every daemon of the fleet shares them): each fits LCM's length and is
// none of the daemon's other channels (with its prefix), nor the other fleet channel.
void check_fleet_channels(Section& s, const Channels& c, const std::vector<std::pair<std::string, std::string>>& inputs,
                          const std::vector<std::pair<std::string, std::string>>& outputs) {
  constexpr size_t kLcmMaxChannel = 63;
  for (const auto& [key, name] : {std::pair{"fleet", c.fleet}, std::pair{"fleet_control", c.fleet_control}}) {
    if (name.size() > kLcmMaxChannel)
      throw s.error_at(s.place_of(key), "'" + s.path() + "." + key + "': channel '" + name + "' is longer than LCM's " +
                                            std::to_string(kLcmMaxChannel) + " characters");
    for (const auto* list : {&inputs, &outputs})
      for (const auto& [other, other_name] : *list)
        if (c.full(other_name) == name)
          throw s.error_at(s.place_of(key), "'" + s.path() + "." + key + "': the same channel as " + s.path() + "." +
                                                other + " ('" + name + "')");
  }
  if (c.fleet == c.fleet_control)
    throw s.error_at(s.place_of("fleet_control"), "'" + s.path() + ".fleet_control': the same channel as " + s.path() +
                                                      ".fleet ('" + c.fleet + "')");
}

void check_channels(Section& s, const Channels& c) {
  constexpr size_t kLcmMaxChannel = 63;  // LCM_MAX_CHANNEL_NAME_LENGTH
  using Named = std::vector<std::pair<std::string, std::string>>;
  Named inputs{{"odometry", c.odometry}, {"landmarks", c.landmarks},
               {"bearings", c.bearings}, {"loop_closures", c.loop_closures},
               {"imu", c.imu},           {"gnss", c.gnss}};
  Named outputs{{"fused_pose", c.fused_pose}, {"fused_geo", c.fused_geo},           {"trajectory", c.trajectory},
                {"targets", c.targets},       {"match_requests", c.match_requests}, {"landmark_map", c.landmark_map},
                {"status", c.status}};
  // The estimators that are not primary publish on FUSED_POSE_<ESTIMATOR> (publisher.hpp).
  for (const char* e : {"_DEAD_RECKONING", "_EKF", "_PF", "_GRAPH", "_INERTIAL"})
    outputs.push_back({"fused_pose", c.fused_pose + e});
  for (const Named* list : {&inputs, &outputs})
    for (const auto& [key, name] : *list)
      if (c.full(name).size() > kLcmMaxChannel)
        throw s.error_at(c.prefix.size() > name.size() ? s.place_of("prefix") : s.place_of(key),
                         "'" + s.path() + "." + key + "': channel '" + c.full(name) + "' is " +
                             std::to_string(c.full(name).size()) + " characters with the prefix; LCM allows " +
                             std::to_string(kLcmMaxChannel));
  for (size_t i = 0; i < inputs.size(); ++i)
    for (size_t j = 0; j < i; ++j)
      if (inputs[i].second == inputs[j].second)
        throw s.error_at(s.place_of(inputs[i].first), "'" + s.path() + "." + inputs[i].first +
                                                          "': the same channel as " + s.path() + "." + inputs[j].first +
                                                          " ('" + c.full(inputs[i].second) +
                                                          "'); every input needs a channel of its own");
  for (const auto& [okey, oname] : outputs)
    for (const auto& [ikey, iname] : inputs)
      if (oname == iname)
        throw s.error_at(s.place_of(okey), "'" + s.path() + "." + okey + "': output channel '" + c.full(oname) +
                                               "' is also the input " + s.path() + "." + ikey +
                                               " (the daemon would read its own output)");
  for (size_t i = 0; i < outputs.size(); ++i)
    for (size_t j = 0; j < i; ++j)
      if (outputs[i].second == outputs[j].second)
        throw s.error_at(s.place_of(outputs[i].first), "'" + s.path() + "." + outputs[i].first +
                                                           "': the same channel as " + s.path() + "." +
                                                           outputs[j].first + " ('" + c.full(outputs[i].second) + "')");
  check_fleet_channels(s, c, inputs, outputs);
}

void read_channels(Section s, Channels& c) {
  s.get("prefix", c.prefix, Check<std::string>([](const std::string& v) -> std::optional<std::string> {
          return v.empty() ? std::nullopt : channel_name()(v);  // empty: no prefix
        }));
  for (auto [key, field] : {std::pair{"odometry", &c.odometry},
                            {"landmarks", &c.landmarks},
                            {"bearings", &c.bearings},
                            {"loop_closures", &c.loop_closures},
                            {"imu", &c.imu},
                            {"gnss", &c.gnss},
                            {"fused_pose", &c.fused_pose},
                            {"fused_geo", &c.fused_geo},
                            {"trajectory", &c.trajectory},
                            {"targets", &c.targets},
                            {"match_requests", &c.match_requests},
                            {"landmark_map", &c.landmark_map},
                            {"status", &c.status},
                            {"fleet", &c.fleet},
                            {"fleet_control", &c.fleet_control}})
    s.get(key, *field, channel_name());
  s.reject_unknown_keys();
  check_channels(s, c);
}

}  // namespace

uint64_t engine_fingerprint(const engine::EngineConfig& engine) {
  // Of the parsed values, not the text: a default written out or left out, comments and layout do not count.
  return FieldHash().add(engine).value();
}

void read_engine_config(Section& s, engine::EngineConfig& c) {
  s.get_parsed("primary_estimator", c.primary_estimator, engine::primary_estimator_from_name);
  {
    Section dr = s.child("dead_reckoning");
    read_stage_config(dr, c.dead_reckoning);
  }
  {
    Section f = s.child("filter");
    read_stage_config(f, c.filter);
  }
  {
    Section g = s.child("graph");
    read_stage_config(g, c.graph);
  }
  {
    Section a = s.child("association");
    read_stage_config(a, c.association);
  }
  {
    Section i = s.child("inertial");
    read_stage_config(i, c.inertial);
  }
  s.reject_unknown_keys();
}

static void read_plausibility(Section p, Plausibility& c) {
  p.get("max_position_m", c.max_position_m, in_range(1, 1e12));
  p.get("max_speed_planar_mps", c.max_speed_planar_mps, in_range(1e-3, 1e6));
  p.get("max_speed_spatial_mps", c.max_speed_spatial_mps, in_range(1e-3, 1e6));
  p.get("max_jump_m", c.max_jump_m, in_range(0, 1e9));
  p.get("max_planar_tilt_rad", c.max_planar_tilt_rad, in_range(0, M_PI));
  p.get("max_range_m", c.max_range_m, in_range(1e-3, 1e12));
  p.get("min_variance", c.min_variance, in_range(1e-300, 1));
  p.get("max_variance", c.max_variance, in_range(1, 1e300));
  p.get("max_condition", c.max_condition, in_range(1, 1e300));
  p.get("max_angular_rate_radps", c.max_angular_rate_radps, in_range(1e-3, 1e6));
  p.get("max_acceleration_mps2", c.max_acceleration_mps2, in_range(1e-3, 1e9));
  p.reject_unknown_keys();
}

// engine.graph.fleet.exchange, when enabled, is this daemon's: daemon.name must be one of its members, and is its name
// there (FleetExchangeOptions::self).
static void check_fleet_member(const YAML::Node& root, const std::string& file, DaemonConfig& c) {
  engine::FleetExchangeOptions& x = c.engine.graph.fleet_exchange;
  if (!x.enabled) return;
  if (std::find(x.members.begin(), x.members.end(), c.name) == x.members.end()) {
    Section s(root["engine"]["graph"]["fleet"]["exchange"], "engine.graph.fleet.exchange", file);
    throw s.error_at(s.place_of("members"),
                     "'engine.graph.fleet.exchange.members': daemon.name '" + c.name + "' is not among the members");
  }
  x.self = c.name;
}

static void read_daemon_config(const YAML::Node& root, const std::string& file, DaemonConfig& c) {
  Section top(root, "", file);
  {
    Section d = top.child("daemon");
    d.get("name", c.name, Check<std::string>([](const std::string& v) -> std::optional<std::string> {
            if (v.empty() || v.size() > 64) return "must be 1 to 64 characters";
            for (unsigned char ch : v)
              if (ch < 0x20 || ch == 0x7f) return "must not contain control characters";
            return std::nullopt;
          }));
    d.get("lcm_url", c.lcm_url);
    d.get("status_period_s", c.status_period_s, in_range(0.05, 3600));
    d.get("queue_capacity", c.queue_capacity, int_in_range(1, 1 << 20));
    d.get("publish_queue_capacity", c.publish_queue_capacity, int_in_range(1, 1 << 20));
    d.get("record", c.record);
    d.get("log_rate_limit_s", c.log_rate_limit_s, non_negative());
    d.get("max_ahead_s", c.max_ahead_s, positive());
    d.get("time_resync_messages", c.time_resync_messages, int_in_range(1, 1000000));
    d.get("max_ahead_of_wall_s", c.max_ahead_of_wall_s, positive());
    d.get("max_sources", c.max_sources, int_in_range(1, 1 << 20));
    d.get("source_idle_s", c.source_idle_s, non_negative());
    d.get("source_evict_idle_s", c.source_evict_idle_s, non_negative());
    d.get("drain_timeout_s", c.drain_timeout_s, non_negative());
    d.get("state_dir", c.state_dir);
    d.get("state_period_s", c.state_period_s, in_range(0.1, 86400));
    d.get("source_handover_s", c.source_handover_s, non_negative());
    read_plausibility(d.child("plausibility"), c.plausibility);
    d.reject_unknown_keys();
  }
  read_channels(top.child("channels"), c.channels);
  {
    Section e = top.child("engine");
    read_engine_config(e, c.engine);
  }
  top.reject_unknown_keys();
  check_fleet_member(root, file, c);
  c.engine_fingerprint = engine_fingerprint(c.engine);
}

namespace {

constexpr int64_t kMaxConfigNodes = 1'000'000;  // nodes walked, aliases counted each time they are reached

// A control character (other than tab, newline and carriage return) anywhere in the text: a NUL in a name, an
// escape sequence in a log.  Named by line and column.
void refuse_control_characters(const std::string& text, const std::string& file) {
  int line = 1, column = 1;
  for (unsigned char ch : text) {
    if (ch < 0x20 && ch != '\t' && ch != '\n' && ch != '\r') {
      std::ostringstream s;
      s << file << ":" << line << ":" << column << ": control character 0x" << std::hex << static_cast<int>(ch)
        << " in the config (only tab, newline and carriage return are allowed)";
      throw ConfigError(s.str());
    }
    if (ch == '\n')
      ++line, column = 1;
    else
      ++column;
  }
}

// A second YAML document (yaml-cpp's Load reads the first and ignores the rest): a "---" line after content, or
// content after a "..." line.  Found in the text: yaml-cpp's LoadAll does not return on some malformed input.
void refuse_second_document(const std::string& text, const std::string& file) {
  bool content = false, ended = false;
  int line = 0;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) {
    ++line;
    const auto marker = [&](const char* m) {
      return l.rfind(m, 0) == 0 && (l.size() == 3 || l[3] == ' ' || l[3] == '\t' || l[3] == '#' || l[3] == '\r');
    };
    const bool blank = l.find_first_not_of(" \t\r") == std::string::npos || l[l.find_first_not_of(" \t\r")] == '#';
    if ((marker("---") && content) || (ended && !blank && !marker("..."))) {
      std::ostringstream s;
      s << file << ":" << line << ": a second YAML document; a config is one document";
      throw ConfigError(s.str());
    }
    if (marker("..."))
      ended = true;
    else if (!blank && !marker("---"))
      content = true;
  }
}

// Text that yaml-cpp reads as no document at all (a lone ',', say) although it holds more than comments and markers:
// an error at its first such line, not an empty configuration.
void refuse_content_without_document(const std::string& text, const std::string& file) {
  int line = 0;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) {
    ++line;
    const auto first = l.find_first_not_of(" \t\r");
    if (first == std::string::npos || l[first] == '#' || l.rfind("---", 0) == 0 || l.rfind("...", 0) == 0) continue;
    std::ostringstream s;
    s << file << ":" << line << ":" << first + 1 << ": no YAML document could be read from '" << l.substr(first, 40)
      << "' (expected a map of sections: daemon, channels, engine)";
    throw ConfigError(s.str());
  }
}

// A key written twice in one mapping (yaml-cpp keeps the first and ignores the rest): an error at the second.
// Aliases make a node reachable many times (a "billion laughs" document): past `budget` visits the walk stops with
// an error instead of taking exponential time.
void refuse_duplicate_keys(const YAML::Node& node, const std::string& file, int64_t& budget) {
  if (--budget < 0) {
    std::ostringstream s;
    s << file << ":" << node.Mark().line + 1 << ": the document expands beyond " << kMaxConfigNodes
      << " nodes (aliases of aliases?)";
    throw ConfigError(s.str());
  }
  if (node.IsSequence()) {
    for (const auto& child : node) refuse_duplicate_keys(child, file, budget);
    return;
  }
  if (!node.IsMap()) return;
  std::set<std::string> seen;
  for (const auto& kv : node) {
    if (kv.first.IsScalar() && !seen.insert(kv.first.Scalar()).second) {
      std::ostringstream s;
      s << file << ":" << kv.first.Mark().line + 1 << ":" << kv.first.Mark().column + 1 << ": key '"
        << kv.first.Scalar() << "' written twice in one section (the second would be ignored)";
      throw ConfigError(s.str());
    }
    refuse_duplicate_keys(kv.second, file, budget);
  }
}

}  // namespace

DaemonConfig parse_daemon_config(const std::string& yaml_text, const std::string& file) {
  if (yaml_text.size() > kMaxConfigBytes)
    throw ConfigError(file + ": " + std::to_string(yaml_text.size()) + " bytes; a config is at most " +
                      std::to_string(kMaxConfigBytes));
  refuse_control_characters(yaml_text, file);
  refuse_second_document(yaml_text, file);
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    std::ostringstream s;
    s << file << ":" << e.mark.line + 1 << ":" << e.mark.column + 1 << ": YAML syntax error: " << e.msg;
    throw ConfigError(s.str());
  }
  if (root.IsNull()) refuse_content_without_document(yaml_text, file);
  if (root.IsDefined() && !root.IsNull() && !root.IsMap()) {  // a scalar or a list: no section can be read from it
    std::ostringstream s;
    s << file << ":" << root.Mark().line + 1 << ":" << root.Mark().column + 1
      << ": expected a map of sections (daemon, channels, engine), got "
      << (root.IsScalar() ? "'" + root.Scalar() + "'" : std::string("a list"));
    throw ConfigError(s.str());
  }
  int64_t budget = kMaxConfigNodes;
  refuse_duplicate_keys(root, file, budget);
  DaemonConfig c;
  try {
    read_daemon_config(root, file, c);
  } catch (const YAML::Exception& e) {
    // A YAML construct no reader expected (a key that is a list, a tag yaml-cpp cannot convert): still the file's
    // error, with the place yaml-cpp knows.
    std::ostringstream s;
    s << file;
    if (e.mark.line >= 0) s << ":" << e.mark.line + 1 << ":" << e.mark.column + 1;
    s << ": " << e.msg;
    throw ConfigError(s.str());
  }
  return c;
}

DaemonConfig load_daemon_config(const std::string& path) {
  // Only a regular file (not a FIFO that blocks for ever, not /dev/zero), read up to the size limit.
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) throw ConfigError(path + ": cannot open config file");
  if (std::filesystem::is_directory(status)) throw ConfigError(path + ": a directory, not a config file");
  if (!std::filesystem::is_regular_file(status)) throw ConfigError(path + ": not a regular file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError(path + ": cannot open config file");
  std::string text(kMaxConfigBytes + 1, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<size_t>(in.gcount()));
  return parse_daemon_config(text, path);
}

}  // namespace sextant::config
