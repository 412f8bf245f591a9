#pragma once
#include "assoc/tuple_costs.hpp"

#include <string>
#include <vector>

namespace sextant::engine {

/// The S-D assignment solver of the association stage (config key `engine.association.solver`).
enum class AssociationSolver {
  kLagrangian,  // "lr": Lagrangian relaxation (assoc::solve_sd_lagrangian)
  kExact,       // "exact": branch and bound (assoc::solve_sd_exact; small scans only)
};
/// The kind of a config spelling; throws std::invalid_argument naming the spellings for any other name.
AssociationSolver association_solver_from_name(const std::string& name);
const char* association_solver_name(AssociationSolver solver);

/// Multi-sensor passive association: bearing scans grouped by scan_id, associated by S-D assignment, triangulated.
struct AssociationConfig {
  bool enabled = true;
  assoc::CostKind cost = assoc::CostKind::kClassic;  // classic | kl | renyi (assoc/tuple_costs.hpp)
  double alpha = 0.5;                                // Renyi order
  double p_detect = 0.9;
  double clutter_density = 1.0;  // false alarms per rad^2, the same for every sensor (when no region is given)
  // The surveillance region, an axis-aligned box [region_min, region_max] (world frame, metres; both empty or both
  // 3 numbers).  With it, each sensor's false-alarm density is false_alarms_per_scan / the area of its field of
  // view over the region (assoc/field_of_view.hpp, padded by 5 times the sensor's largest detection sigma), and
  // the target prior is available.
  std::vector<double> region_min, region_max;
  double false_alarms_per_scan = 0;  // expected false alarms per sensor and scan; > 0 needs the region
  bool target_prior = false;         // add the target-prior term (assoc/tuple_costs.hpp); needs the region
  double expected_targets = 1;       // targets expected in the region (mu_T = this / region volume)
  double gate_probability = 0.9999;
  AssociationSolver solver = AssociationSolver::kLagrangian;
  int max_iterations = 100;
  double gap_tolerance = 0.01;  // absolute duality gap, cost units (assoc/sd_assignment.hpp)
  int expected_sensors =
      0;  // associate a scan_id as soon as this many sensors reported (0: when the next scan_id arrives)
  int max_pending_scans = 16;  // scan_ids waiting for sensors; beyond this the oldest is associated as it is
  // Scan ids are one numbering for all sensors, so one scan numbered far from the others (INT64_MAX, a far jump)
  // would make every later scan "late".  A scan_id more than `max_scan_id_jump` away from the newest accepted one
  // (ahead or behind) is refused and counted (scan_id_jumps) without moving the numbering; `scan_id_resync_after`
  // consecutive such scans that agree (non-decreasing, each within max_scan_id_jump of the one before) are a true
  // renumbering: the last of them is taken (scan_id_resyncs), the groups of the old numbering are associated first.
  // 0: no check (scan ids that are not consecutive counters, e.g. times).
  int max_scan_id_jump = 1000;
  int scan_id_resync_after = 5;
};

}  // namespace sextant::engine
