#include "daemon/config/stage_config_readers.hpp"

#include <cmath>
#include <cstdlib>

namespace sextant::config {

void read_stage_config(Section& s, engine::GraphConfig& c) {
  s.get("enabled", c.enabled);
  {
    Section k = s.child("keyframes");
    k.get("k1", c.keyframes.k1, non_negative());
    k.get("k2", c.keyframes.k2, positive());
    k.get("translation_weight", c.keyframes.translation_weight, non_negative());
    k.get("rotation_weight", c.keyframes.rotation_weight, non_negative());
    k.get("reanchor_after", c.keyframes.reanchor_after, int_in_range(0, 1 << 20));
    if (!(c.keyframes.k1 < c.keyframes.k2)) throw k.error("'" + k.path() + "': k1 must be smaller than k2");
    if (c.keyframes.translation_weight == 0 && c.keyframes.rotation_weight == 0)
      throw k.error("'" + k.path() + "': translation_weight and rotation_weight cannot both be 0");
    k.reject_unknown_keys();
  }
  {
    Section p = s.child("loops");
    p.get("propose", c.propose_loops);
    p.get("n1", c.proposals.n1, int_in_range(0, 1000));
    p.get("n2", c.proposals.n2, int_in_range(-1, 1000));
    int seed = static_cast<int>(c.proposals.seed);
    p.get("seed", seed, int_in_range(0, 2147483647));
    c.proposals.seed = static_cast<uint64_t>(seed);
    p.get("robust", c.robust, one_of({"none", "huber", "cauchy", "dcs"}));
    // "auto" (a chi-square quantile of the loops' dimension, kernel_width_for in graph_stage_config.hpp) or a number.
    std::string width;  // stays empty when the key is absent (the default stays)
    p.get("kernel_width", width, Check<std::string>([](const std::string& v) -> std::optional<std::string> {
      if (v == "auto") return std::nullopt;
      char* end = nullptr;
      const double x = std::strtod(v.c_str(), &end);
      if (end == v.c_str() || *end != '\0' || !std::isfinite(x) || !(x > 0))
        return "expected 'auto' or a positive number, got '" + v + "'";
      return std::nullopt;
    }));
    if (width == "auto") c.kernel_width.reset();
    else if (!width.empty()) c.kernel_width = std::strtod(width.c_str(), nullptr);
    p.get("gate_probability", c.loop_gate_probability, in_range(0.5, 0.999999999));
    p.get("gate_odometry_scale", c.loop_gate_odometry_scale, positive());
    p.get("time_tolerance_s", c.loop_time_tolerance_s, non_negative());
    p.reject_unknown_keys();
  }
  {
    Section l = s.child("landmarks");
    l.get("enabled", c.landmarks.enabled);
    l.get("robust", c.landmarks.robust);
    l.get("gate_probability", c.landmarks.gate_probability, in_range(0.5, 0.999999999));
    l.get("gate_odometry_scale", c.landmarks.gate_odometry_scale, positive());
    l.get("max_waiting", c.landmarks.max_waiting, int_in_range(0, 1 << 20));
    l.reject_unknown_keys();
  }
  s.get("relinearize_translation", c.relinearize_translation, positive());
  s.get("relinearize_rotation", c.relinearize_rotation, positive());
  s.get("min_increment_variance", c.min_increment_variance, positive());
  s.get("odometry_history", c.odometry_history, int_in_range(1, 100000000));
  s.get("coalesce_odometry", c.coalesce_odometry);
  s.get("odometry_batch_max", c.odometry_batch_max, int_in_range(1, 1 << 20));
  s.get("trajectory_max_keyframes", c.trajectory_max_keyframes, int_in_range(1, 1 << 20));
  s.reject_unknown_keys();
}

}  // namespace sextant::config
