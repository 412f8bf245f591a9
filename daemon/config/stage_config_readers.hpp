#pragma once
// One reader per stage config (each in its own file next to this one), called by read_engine_config.
#include "daemon/config/config_reader.hpp"
#include "daemon/engine/engine_config.hpp"

namespace sextant::config {

void read_stage_config(Section& section, engine::DeadReckoningConfig& config);
void read_stage_config(Section& section, engine::FilterConfig& config);
void read_stage_config(Section& section, engine::AssociationConfig& config);
void read_stage_config(Section& section, engine::GraphConfig& config);
void read_stage_config(Section& section, engine::InertialConfig& config);

}  // namespace sextant::config
