#include "daemon/config/daemon_config.hpp"

#include "daemon/config/stage_config_readers.hpp"

#include <fstream>
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

void read_channels(Section s, Channels& c) {
  s.get("prefix", c.prefix);
  for (auto [key, field] : {std::pair{"odometry", &c.odometry}, {"landmarks", &c.landmarks}, {"bearings", &c.bearings},
                            {"loop_closures", &c.loop_closures}, {"fused_pose", &c.fused_pose},
                            {"trajectory", &c.trajectory}, {"targets", &c.targets},
                            {"match_requests", &c.match_requests}, {"status", &c.status}})
    s.get(key, *field, channel_name());
  s.reject_unknown_keys();
}

}  // namespace

void read_engine_config(Section& s, engine::EngineConfig& c) {
  s.get("primary_estimator", c.primary_estimator, one_of({"auto", "dead_reckoning", "ekf", "pf", "graph"}));
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
  s.reject_unknown_keys();
}

DaemonConfig parse_daemon_config(const std::string& yaml_text, const std::string& file) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::ParserException& e) {
    std::ostringstream s;
    s << file << ":" << e.mark.line + 1 << ":" << e.mark.column + 1 << ": YAML syntax error: " << e.msg;
    throw ConfigError(s.str());
  }
  DaemonConfig c;
  Section top(root, "", file);
  {
    Section d = top.child("daemon");
    d.get("name", c.name, Check<std::string>([](const std::string& v) -> std::optional<std::string> {
            if (v.empty() || v.size() > 64) return "must be 1 to 64 characters";
            return std::nullopt;
          }));
    d.get("lcm_url", c.lcm_url);
    d.get("status_period_s", c.status_period_s, in_range(0.05, 3600));
    d.get("queue_capacity", c.queue_capacity, int_in_range(1, 1 << 20));
    d.get("publish_queue_capacity", c.publish_queue_capacity, int_in_range(1, 1 << 20));
    d.get("record", c.record);
    d.get("log_rate_limit_s", c.log_rate_limit_s, non_negative());
    d.reject_unknown_keys();
  }
  read_channels(top.child("channels"), c.channels);
  {
    Section e = top.child("engine");
    read_engine_config(e, c.engine);
  }
  top.reject_unknown_keys();
  return c;
}

DaemonConfig load_daemon_config(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path + ": cannot open config file");
  std::stringstream buf;
  buf << in.rdbuf();
  return parse_daemon_config(buf.str(), path);
}

}  // namespace sextant::config
