#include "daemon/config/stage_config_readers.hpp"

namespace sextant::config {

void read_stage_config(Section& s, engine::AssociationConfig& c) {
  s.get("enabled", c.enabled);
  s.get("cost", c.cost, one_of({"classic", "kl", "renyi"}));
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
  s.get("solver", c.solver, one_of({"lr", "exact"}));
  s.get("max_iterations", c.max_iterations, int_in_range(1, 100000));
  s.get("gap_tolerance", c.gap_tolerance, non_negative());
  s.get("expected_sensors", c.expected_sensors, int_in_range(0, 64));
  s.get("max_pending_scans", c.max_pending_scans, int_in_range(1, 4096));
  s.reject_unknown_keys();
}

}  // namespace sextant::config
