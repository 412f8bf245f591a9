#pragma once
#include <string>

namespace sextant::engine {

/// Multi-sensor passive association: bearing scans grouped by scan_id, associated by S-D assignment, triangulated.
struct AssociationConfig {
  bool enabled = true;
  std::string cost = "classic";    // classic | kl | renyi
  double alpha = 0.5;              // Renyi order
  double p_detect = 0.9;
  double clutter_density = 1.0;    // false alarms per rad^2
  double gate_probability = 0.9999;
  std::string solver = "lr";       // lr (Lagrangian relaxation) | exact (branch and bound; small scans only)
  int max_iterations = 100;
  double gap_tolerance = 0.01;
  int expected_sensors = 0;        // associate a scan_id as soon as this many sensors reported (0: when the next scan_id arrives)
  int max_pending_scans = 16;      // scan_ids waiting for sensors; beyond this the oldest is associated as it is
};

}  // namespace sextant::engine
