// The filter stage's state in the state directory (filter_stage.hpp, save/load; README "State directory").
#include "daemon/engine/event_archive.hpp"
#include "daemon/engine/filter_stage.hpp"

namespace sextant::engine {

void FilterStage::Track::save(archive::ArchiveWriter& w) const {
  w(fusion)(pending)(
      predictions)(updates)(gated)(new_landmarks)(unknown)(rejected)(before_odometry)(associated)(tentative)(duplicates)(unknown_sources)(stale_sightings)(over_budget)(exhausted);
}

void FilterStage::Track::load(archive::ArchiveReader& r) {
  r(fusion)(pending)(
      predictions)(updates)(gated)(new_landmarks)(unknown)(rejected)(before_odometry)(associated)(tentative)(duplicates)(unknown_sources)(stale_sightings)(over_budget)(exhausted);
}

void FilterStage::SpatialTrack::save(archive::ArchiveWriter& w) const {
  w(fusion)(pending)(
      predictions)(updates)(gated)(new_landmarks)(rejected)(before_odometry)(duplicates)(unidentified)(unfused)(stale_sightings)(over_budget);
}

void FilterStage::SpatialTrack::load(archive::ArchiveReader& r) {
  r(fusion)(pending)(
      predictions)(updates)(gated)(new_landmarks)(rejected)(before_odometry)(duplicates)(unidentified)(unfused)(stale_sightings)(over_budget);
}

void FilterStage::save(archive::ArchiveWriter& w) {
  w(static_cast<uint64_t>(histories_.size()));
  for (const auto& [body, h] : histories_) w(body)(h);
  w(static_cast<uint64_t>(spatial_.size()));
  for (const auto& [body, h] : spatial_) w(body)(h);
  w(published_)(mixed_)(before_odometry_)(too_late_)(reapplied_);
}

void FilterStage::load(archive::ArchiveReader& r) {
  const auto window = static_cast<int64_t>(config_.history_s * 1e6);
  histories_.clear();
  spatial_.clear();
  const uint64_t n = r.count(1, "the planar bodies");
  for (uint64_t i = 0; i < n; ++i) {
    const auto body = r.get<std::string>();
    const Track fresh = new_track(body);
    auto it = histories_.try_emplace(body, window, fresh).first;
    it->second.load(r, fresh);
  }
  const uint64_t m = r.count(1, "the 3-D bodies");
  for (uint64_t i = 0; i < m; ++i) {
    const auto body = r.get<std::string>();
    const SpatialTrack fresh = new_spatial_track();
    auto it = spatial_.try_emplace(body, window, fresh).first;
    it->second.load(r, fresh);
  }
  r(published_)(mixed_)(before_odometry_)(too_late_)(reapplied_);
}

}  // namespace sextant::engine
