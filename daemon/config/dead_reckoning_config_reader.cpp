#include "daemon/config/stage_config_readers.hpp"

namespace sextant::config {

void read_stage_config(Section& s, engine::DeadReckoningConfig& c) {
  s.get("enabled", c.enabled);
  s.get("min_increment_variance", c.min_increment_variance, non_negative());
  s.get("max_gap_s", c.max_gap_s, positive());
  s.reject_unknown_keys();
}

}  // namespace sextant::config
