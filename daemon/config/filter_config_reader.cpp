#include "daemon/config/stage_config_readers.hpp"
#include "estimators/filter/multi_source_ekf.hpp"

#include <algorithm>
#include <set>

namespace sextant::config {

namespace {

// sources: {NAME: {body, predict, fuse: [x, y, yaw, vx, vy, vyaw], differential, gate, timeout_s}}
void read_odometry_sources(Section& s, engine::FilterConfig& c) {
  Section list = s.child("sources");
  if (!list.node().IsDefined() || list.node().IsNull()) return;
  if (!list.node().IsMap()) throw list.error("'" + list.path() + "': expected a map of source name -> settings");
  const std::vector<std::string> names{"x", "y", "yaw", "vx", "vy", "vyaw"};
  for (const YAML::Node& key : list.keys()) {
    const auto name = key.Scalar();
    Section e = list.child(name);
    engine::FilterConfig::OdometrySource o;
    e.get("body", o.body);
    e.get("predict", o.predict);
    std::vector<std::string> fuse;
    e.get("fuse", fuse);
    if (e.node()["fuse"].IsDefined()) {
      o.fuse.fill(false);
      for (const auto& f : fuse) {
        const auto at = std::find(names.begin(), names.end(), f);
        if (at == names.end())
          throw e.error_at(e.node()["fuse"],
                           "'" + e.path() + ".fuse': unknown component '" + f + "' (x, y, yaw, vx, vy, vyaw)");
        o.fuse[static_cast<size_t>(at - names.begin())] = true;
      }
    }
    e.get("differential", o.differential);
    e.get("gate", o.gate, non_negative());
    e.get("timeout_s", o.timeout_s, non_negative());
    e.reject_unknown_keys();
    if (o.body.empty()) o.body = name;
    c.sources[name] = o;
  }
  // Each body's sources must make a valid filter; a body without a predicting source gets the unlisted source of
  // its own name as its predictor.
  std::map<std::string, std::map<std::string, filter::OdometrySourceOptions>> bodies;
  for (const auto& [name, o] : c.sources)
    bodies[o.body][name] = {o.predict, o.fuse, o.differential, o.gate, o.timeout_s};
  for (auto& [body, sources] : bodies) {
    const bool has_predictor =
        std::any_of(sources.begin(), sources.end(), [](const auto& kv) { return kv.second.predict; });
    if (!has_predictor && !c.sources.contains(body)) sources[body].predict = true;
    try {
      filter::MultiSourceEkf::validate(sources);
    } catch (const std::invalid_argument& ex) {
      throw list.error("'" + list.path() + "': body '" + body + "': " + ex.what());
    }
  }
}

}  // namespace

void read_stage_config(Section& s, engine::FilterConfig& c) {
  s.get_parsed("type", c.type, engine::filter_type_from_name);
  s.get("slam", c.slam);
  s.get("gate", c.gate, positive());
  s.get("initial_sigma_xy", c.initial_sigma_xy, positive());
  s.get("initial_sigma_theta", c.initial_sigma_theta, positive());
  s.get("min_increment_variance", c.min_increment_variance, positive());
  s.get("max_landmarks", c.max_landmarks, int_in_range(1, 1 << 20));
  s.get("history_s", c.history_s, in_range(0, 60));
  // map: a list of [id, x, y]
  std::vector<std::vector<double>> rows;
  s.get("map", rows);
  std::set<int64_t> ids;
  const YAML::Node node = s.node().IsMap() ? s.node()["map"] : YAML::Node();
  for (size_t i = 0; i < rows.size(); ++i) {
    const auto& r = rows[i];
    const YAML::Node at = node.IsSequence() ? node[i] : node;
    if (r.size() != 3 || !std::isfinite(r[1]) || !std::isfinite(r[2]) || r[0] != std::floor(r[0]) || r[0] < 0)
      throw s.error_at(
          at, "'" + s.path() + ".map[" + std::to_string(i) + "]': expected [id, x, y] with a non-negative integer id");
    if (!ids.insert(static_cast<int64_t>(r[0])).second)
      throw s.error_at(at, "'" + s.path() + ".map[" + std::to_string(i) + "]': landmark id " +
                               std::to_string(static_cast<int64_t>(r[0])) + " listed twice");
    c.map.push_back({static_cast<int64_t>(r[0]), r[1], r[2]});
  }
  Section pf = s.child("pf");
  pf.get("particles", c.pf.particles, int_in_range(1, 1000000));
  pf.get("resample_threshold", c.pf.resample_threshold, in_range(0, 1));
  pf.get("seed", c.pf.seed);
  pf.get("confirmations", c.pf.confirmations, int_in_range(1, 1000000));
  pf.get("tentative_lifetime", c.pf.tentative_lifetime, int_in_range(1, 1000000));
  pf.reject_unknown_keys();
  read_odometry_sources(s, c);
  s.reject_unknown_keys();
}

}  // namespace sextant::config
