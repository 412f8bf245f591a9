// Defaults are the same whether a key of config/default.yaml is written or left out: for every key of the file (each
// leaf and each block), the file without that key parses to the same configuration, field by field
// (aggregate_equal.hpp), as the whole file.  A struct default that disagrees with default.yaml (a config without
// `primary_estimator` once put the graph on FUSED_POSE where the file says the EKF) fails here, naming the key.
#include "aggregate_equal.hpp"
#include "daemon/config/daemon_config.hpp"
#include "daemon/config/engine_config_fields.hpp"

#include <doctest/doctest.h>

#include <yaml-cpp/yaml.h>

#include <fstream>
#include <sstream>

using namespace sextant;

namespace {

// Every key path of `node` (maps only), blocks before their keys.
void key_paths(const YAML::Node& node, std::vector<std::string>& path, std::vector<std::vector<std::string>>& out) {
  if (!node.IsMap()) return;
  for (const auto& kv : node) {
    path.push_back(kv.first.as<std::string>());
    out.push_back(path);
    key_paths(kv.second, path, out);
    path.pop_back();
  }
}

// A deep copy of `node` without the key at `path`.
YAML::Node without(const YAML::Node& node, const std::vector<std::string>& path) {
  YAML::Node copy = YAML::Clone(node);
  YAML::Node parent = copy;
  for (size_t i = 0; i + 1 < path.size(); ++i) parent.reset(parent[path[i]]);
  parent.remove(path.back());
  return copy;
}

}  // namespace

TEST_CASE("config: every key of config/default.yaml left out gives the same configuration as written") {
  const std::string file = std::string(SEXTANT_SOURCE_DIR) + "/config/default.yaml";
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  const YAML::Node root = YAML::Load(text.str());
  config::DaemonConfig full = config::parse_daemon_config(text.str(), file);
  // The state fingerprint is of the parsed engine config: compared with the rest below, it must not depend on which
  // defaults are written (a state saved under a config that writes a default was refused under one that does not).
  CHECK(full.engine_fingerprint == config::engine_fingerprint(engine::EngineConfig{}));

  // The comparison itself can fail: one changed value is found.
  {
    config::DaemonConfig changed = full;
    changed.engine.graph.smoother.wildfire = 0.5;
    CHECK_FALSE(testing::first_difference(full, changed).empty());
    changed = full;
    changed.engine.filter.pf.seed = 7;
    CHECK_FALSE(testing::first_difference(full, changed).empty());
  }

  std::vector<std::string> path;
  std::vector<std::vector<std::string>> keys;
  key_paths(root, path, keys);
  CHECK(keys.size() > 100);
  for (const auto& key : keys) {
    std::string name;
    for (const auto& k : key) name += (name.empty() ? "" : ".") + k;
    YAML::Emitter out;
    out << without(root, key);
    config::DaemonConfig omitted;
    try {
      omitted = config::parse_daemon_config(out.c_str(), file + " without " + name);
    } catch (const config::ConfigError& e) {
      FAIL_CHECK(name << ": " << e.what());
      continue;
    }
    const std::string d = testing::first_difference(full, omitted);
    CHECK_MESSAGE(d.empty(), "left out, '" << name << "' gives another configuration (field " << d << ")");
  }
}
