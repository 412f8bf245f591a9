#include "daemon/config/stage_config_readers.hpp"

#include <cmath>

namespace sextant::config {

void read_stage_config(Section& s, engine::AssociationConfig& c) {
  s.get("enabled", c.enabled);
  s.get_parsed("cost", c.cost, assoc::cost_kind_from_string);
  s.get("alpha", c.alpha, Check<double>([](const double& v) -> std::optional<std::string> {
          if (v > 0 && v < 1) return std::nullopt;
          return "must be in (0, 1), got " + std::to_string(v);
        }));
  s.get("p_detect", c.p_detect, Check<double>([](const double& v) -> std::optional<std::string> {
          if (v > 0 && v <= 1) return std::nullopt;
          return "must be in (0, 1], got " + std::to_string(v);
        }));
  s.get("clutter_density", c.clutter_density, positive());
  s.get("gate_probability", c.gate_probability, in_range(0.5, 0.999999999));
  s.get_parsed("solver", c.solver, engine::association_solver_from_name);
  s.get("max_iterations", c.max_iterations, int_in_range(1, 100000));
  s.get("gap_tolerance", c.gap_tolerance, non_negative());
  s.get("expected_sensors", c.expected_sensors, int_in_range(0, 64));
  s.get("max_pending_scans", c.max_pending_scans, int_in_range(1, 4096));
  s.get("max_scan_id_jump", c.max_scan_id_jump, int_in_range(0, 2147483647));
  s.get("scan_id_resync_after", c.scan_id_resync_after, int_in_range(1, 1000));
  const Check<std::vector<double>> point = [](const std::vector<double>& v) -> std::optional<std::string> {
    if (v.empty() || (v.size() == 3 && std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2])))
      return std::nullopt;
    return "expected [x, y, z] (3 finite numbers, metres) or []";
  };
  s.get("region_min", c.region_min, point);
  s.get("region_max", c.region_max, point);
  s.get("false_alarms_per_scan", c.false_alarms_per_scan, non_negative());
  s.get("target_prior", c.target_prior);
  s.get("expected_targets", c.expected_targets, positive());
  s.reject_unknown_keys();
  // Errors that involve several keys, at the line of the key that needs the others.
  const YAML::Node& n = s.node();
  auto at = [&](const char* key) { return n.IsMap() && n[key].IsDefined() ? n[key] : n; };
  if (c.region_min.empty() != c.region_max.empty())
    throw s.error_at(at(c.region_min.empty() ? "region_max" : "region_min"),
                     "'" + s.path() + ".region_min' and '" + s.path() + ".region_max' go together");
  for (size_t i = 0; i < c.region_min.size(); ++i)
    if (!(c.region_min[i] < c.region_max[i]))
      throw s.error_at(at("region_max"), "'" + s.path() +
                                             ".region_max': must be above region_min on every axis (axis " +
                                             std::to_string(i) + ": " + std::to_string(c.region_max[i]) +
                                             " <= " + std::to_string(c.region_min[i]) + ")");
  if (c.false_alarms_per_scan > 0 && c.region_min.empty())
    throw s.error_at(at("false_alarms_per_scan"),
                     "'" + s.path() +
                         ".false_alarms_per_scan': needs region_min and region_max "
                         "(the density is per area of each sensor's field of view over the region)");
  if (c.target_prior && c.region_min.empty())
    throw s.error_at(at("target_prior"), "'" + s.path() +
                                             ".target_prior': needs region_min and region_max (the prior density "
                                             "is expected_targets / region volume)");
}

}  // namespace sextant::config
