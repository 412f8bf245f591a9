#pragma once
// The engine config's parts for aggregate_fields.hpp (the state fingerprint, the config tests): the graph stage's
// config has a base, the SLAM layer's options, which structured bindings cannot see through.
#include "daemon/config/aggregate_fields.hpp"
#include "daemon/engine/engine_config.hpp"

#include <tuple>

template <>
struct sextant::config::aggregate_parts<sextant::engine::GraphConfig> {
  static auto of(const engine::GraphConfig& c) {
    return std::tie(static_cast<const slam::SlamOptions&>(c), c.enabled, c.coalesce_odometry, c.odometry_batch_max,
                    c.odometry_waiting_max, c.odometry_waiting_total_max, c.trajectory, c.fleet_exchange);
  }
};
