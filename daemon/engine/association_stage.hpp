#pragma once
// The association stage: bearing scans of several static passive sensors, grouped by scan_id, become one S-D
// assignment problem (assoc/tuple_costs.hpp, assoc/sd_assignment.hpp); the chosen tuples are published as targets
// with their triangulated position and covariance.  A group is associated when `expected_sensors` have reported,
// when a newer scan_id arrives, or at the end of input.  Groups with fewer than 2 sensors cannot be triangulated
// and are counted, not published.  A scan numbered far from the others is refused unless a run of scans agrees
// on the new numbering (AssociationConfig::max_scan_id_jump).
#include "daemon/engine/association_stage_config.hpp"
#include "daemon/engine/jump_run.hpp"
#include "daemon/engine/stage.hpp"

#include <map>
#include <optional>

namespace sextant::engine {

class AssociationStage final : public Stage {
 public:
  explicit AssociationStage(const AssociationConfig& config) : config_(config) {}
  StageKind kind() const override { return StageKind::kAssociation; }
  bool accepts(const Event& e) const override { return std::holds_alternative<BearingScan>(e); }
  void handle(const Event& e, const Emit& emit) override;
  void finish(const Emit& emit) override;
  Counters counters() const override;
  /// The state directory: the scans waiting for their group, the last associated scan, the counters.
  void save(archive::ArchiveWriter& w) override;
  void load(archive::ArchiveReader& r) override;

 private:
  void associate(int64_t scan_id, const Emit& emit);
  // The scan-id guard (AssociationConfig::max_scan_id_jump): false when the scan is refused as a jump.
  bool admit_scan_id(int64_t scan_id, const Emit& emit);

  AssociationConfig config_;
  std::map<int64_t, std::map<int32_t, BearingScan>> pending_;  // scan_id -> sensor id -> scan
  int64_t last_associated_ = -1;
  // The newest accepted scan id (none before the first scan; on load, from the saved groups), and the run of refused
  // far ones that may be a renumbering.
  std::optional<int64_t> newest_scan_id_;
  JumpRun scan_id_jump_;
  int64_t scan_id_jumps_ = 0, scan_id_resyncs_ = 0;  // not saved (the state's format stays)
  int64_t scans_ = 0, groups_ = 0, targets_ = 0, tuples_ = 0, too_few_sensors_ = 0, late_scans_ = 0, forced_ = 0,
          duplicate_sensor_ = 0;
};

}  // namespace sextant::engine
