#pragma once
// The association stage: bearing scans of several static passive sensors, grouped by scan_id, become one S-D
// assignment problem (assoc/tuple_costs.hpp, assoc/sd_assignment.hpp); the chosen tuples are published as targets
// with their triangulated position and covariance.  A group is associated when `expected_sensors` have reported,
// when a newer scan_id arrives, or at the end of input.  Groups with fewer than 2 sensors cannot be triangulated
// and are counted, not published.
#include "daemon/engine/association_stage_config.hpp"
#include "daemon/engine/stage.hpp"

#include <map>

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

  AssociationConfig config_;
  std::map<int64_t, std::map<int32_t, BearingScan>> pending_;  // scan_id -> sensor id -> scan
  int64_t last_associated_ = -1;
  int64_t scans_ = 0, groups_ = 0, targets_ = 0, tuples_ = 0, too_few_sensors_ = 0, late_scans_ = 0,
          forced_ = 0, duplicate_sensor_ = 0;
};

}  // namespace sextant::engine
