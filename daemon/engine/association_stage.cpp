#include "daemon/engine/association_stage.hpp"

#include "daemon/engine/event_archive.hpp"

#include "assoc/field_of_view.hpp"
#include "assoc/sd_assignment.hpp"

#include <algorithm>
#include <limits>

namespace sextant::engine {

void AssociationStage::handle(const Event& e, const Emit& emit) {
  const auto& scan = std::get<BearingScan>(e);
  ++scans_;
  if (!admit_scan_id(scan.scan_id, emit)) return;
  if (scan.scan_id <= last_associated_) {
    ++late_scans_;  // its group was already associated
    return;
  }
  auto& group = pending_[scan.scan_id];
  if (!group.emplace(scan.sensor_id, scan).second) ++duplicate_sensor_;
  // Older groups are complete once a newer scan_id shows up.
  while (!pending_.empty() && pending_.begin()->first < scan.scan_id) associate(pending_.begin()->first, emit);
  if (config_.expected_sensors > 0 && static_cast<int>(group.size()) >= config_.expected_sensors)
    associate(scan.scan_id, emit);
  while (static_cast<int>(pending_.size()) > config_.max_pending_scans) {
    ++forced_;
    associate(pending_.begin()->first, emit);
  }
}

bool AssociationStage::admit_scan_id(int64_t scan_id, const Emit& emit) {
  if (config_.max_scan_id_jump <= 0) return true;
  const auto window = static_cast<uint64_t>(config_.max_scan_id_jump);
  if (!newest_scan_id_ || value_distance(scan_id, *newest_scan_id_) <= window) {
    scan_id_jump_.accepted();
    newest_scan_id_ = std::max(newest_scan_id_.value_or(scan_id), scan_id);
    return true;
  }
  // Several sensors send the same scan id: equal ids continue a run.
  if (!scan_id_jump_.refused(scan_id, window, config_.scan_id_resync_after, /*allow_equal=*/true)) {
    ++scan_id_jumps_;
    return false;
  }
  // A renumbering: the groups of the old numbering are complete, and this scan starts the new one (after a jump
  // back, ids up to it are new again).
  ++scan_id_resyncs_;
  while (!pending_.empty()) associate(pending_.begin()->first, emit);
  if (scan_id > std::numeric_limits<int64_t>::min()) last_associated_ = std::min(last_associated_, scan_id - 1);
  newest_scan_id_ = scan_id;
  return true;
}

void AssociationStage::finish(const Emit& emit) {
  while (!pending_.empty()) associate(pending_.begin()->first, emit);
}

void AssociationStage::associate(int64_t scan_id, const Emit& emit) {
  auto node = pending_.extract(scan_id);
  last_associated_ = std::max(last_associated_, scan_id);
  const auto& group = node.mapped();
  if (group.size() < 2) {
    ++too_few_sensors_;
    return;
  }
  ++groups_;
  assoc::Scan scan;
  Targets out;
  out.scan_id = scan_id;
  out.cost_kind = assoc::cost_kind_name(config_.cost);
  std::vector<int> sizes;
  for (const auto& [sensor_id, s] : group) {
    out.utime = std::max(out.utime, s.utime);
    out.sensor_ids.push_back(sensor_id);
    scan.sensors.push_back(s.sensor_position);
    std::vector<assoc::Detection> d;
    for (const auto& b : s.detections) d.push_back({b.azimuth, b.elevation, b.sigma_azimuth, b.sigma_elevation});
    sizes.push_back(static_cast<int>(d.size()));
    scan.detections.push_back(std::move(d));
  }
  assoc::CostOptions o;
  o.kind = config_.cost;
  o.alpha = config_.alpha;
  o.p_detect = config_.p_detect;
  o.clutter_density = config_.clutter_density;
  o.gate_probability = config_.gate_probability;
  if (!config_.region_min.empty()) {
    const Eigen::Vector3d lo(config_.region_min[0], config_.region_min[1], config_.region_min[2]);
    const Eigen::Vector3d hi(config_.region_max[0], config_.region_max[1], config_.region_max[2]);
    if (config_.false_alarms_per_scan > 0)
      for (size_t s = 0; s < scan.sensors.size(); ++s) {
        double sigma = 0;  // the field of view is padded by 5 sigma, as in assoc-sim
        for (const auto& d : scan.detections[s]) sigma = std::max({sigma, d.sigma_azimuth, d.sigma_elevation});
        const double area = assoc::field_of_view(scan.sensors[s], lo, hi, 5 * sigma).area();
        o.sensor_clutter_density.push_back(config_.false_alarms_per_scan / std::max(area, 1e-12));
      }
    if (config_.target_prior) o.target_density = config_.expected_targets / (hi - lo).prod();
  }
  const auto tuples = assoc::build_tuples(scan, o);
  tuples_ += static_cast<int64_t>(tuples.size());
  const auto solution = config_.solver == AssociationSolver::kExact
                            ? assoc::solve_sd_exact(tuples, sizes)
                            : assoc::solve_sd_lagrangian(tuples, sizes, config_.max_iterations, config_.gap_tolerance);
  out.total_cost = solution.cost;
  out.duality_gap = solution.gap;
  for (int t : solution.tuples) {
    const auto& tuple = tuples[static_cast<size_t>(t)];
    Target target;
    target.position = tuple.position;
    target.covariance = tuple.covariance;
    target.cost = tuple.cost;
    for (int k : tuple.index) target.detection_indices.push_back(k - 1);  // -1 = missed
    out.targets.push_back(std::move(target));
  }
  targets_ += static_cast<int64_t>(out.targets.size());
  emit(out);
}

Counters AssociationStage::counters() const {
  return {{"scans", scans_},
          {"groups", groups_},
          {"targets", targets_},
          {"tuples", tuples_},
          {"too_few_sensors", too_few_sensors_},
          {"late_scans", late_scans_},
          {"forced_groups", forced_},
          {"duplicate_sensor_scans", duplicate_sensor_},
          {"scan_id_jumps", scan_id_jumps_},
          {"scan_id_resyncs", scan_id_resyncs_}};
}

void AssociationStage::save(archive::ArchiveWriter& w) {
  w(pending_)(last_associated_)(
      scans_)(groups_)(targets_)(tuples_)(too_few_sensors_)(late_scans_)(forced_)(duplicate_sensor_);
}

void AssociationStage::load(archive::ArchiveReader& r) {
  r(pending_)(last_associated_)(
      scans_)(groups_)(targets_)(tuples_)(too_few_sensors_)(late_scans_)(forced_)(duplicate_sensor_);
  // The numbering goes on from the newest scan id the saved state knows (a state saved after a far scan id was
  // associated recovers through a renumbering run).
  newest_scan_id_.reset();
  if (last_associated_ != -1) newest_scan_id_ = last_associated_;
  if (!pending_.empty())
    newest_scan_id_ = std::max(newest_scan_id_.value_or(pending_.rbegin()->first), pending_.rbegin()->first);
}

}  // namespace sextant::engine
