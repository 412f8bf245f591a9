#include "daemon/config/stage_config_readers.hpp"

#include <set>

namespace sextant::config {

void read_stage_config(Section& s, engine::FilterConfig& c) {
  s.get("type", c.type, one_of({"ekf", "pf", "none"}));
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
      throw s.error_at(at, "'" + s.path() + ".map[" + std::to_string(i) + "]': expected [id, x, y] with a non-negative integer id");
    if (!ids.insert(static_cast<int64_t>(r[0])).second)
      throw s.error_at(at, "'" + s.path() + ".map[" + std::to_string(i) + "]': landmark id " + std::to_string(static_cast<int64_t>(r[0])) + " listed twice");
    c.map.push_back({static_cast<int64_t>(r[0]), r[1], r[2]});
  }
  Section pf = s.child("pf");
  pf.get("particles", c.pf.particles, int_in_range(1, 1000000));
  pf.get("resample_threshold", c.pf.resample_threshold, in_range(0, 1));
  pf.get("seed", c.pf.seed);
  pf.get("confirmations", c.pf.confirmations, int_in_range(1, 1000000));
  pf.get("tentative_lifetime", c.pf.tentative_lifetime, int_in_range(1, 1000000));
  pf.reject_unknown_keys();
  s.reject_unknown_keys();
}

}  // namespace sextant::config
