#include "daemon/engine/dead_reckoning_stage.hpp"

#include "daemon/engine/event_archive.hpp"

#include "daemon/engine/pose_conversion.hpp"
#include "daemon/engine/pose_covariance.hpp"

namespace sextant::engine {

Matrix6 DeadReckoningStage::propagate(const Matrix6& previous, const SE3& increment, const Matrix6& q) {
  return compose_covariance(previous, increment, q);
}

void DeadReckoningStage::handle(const Event& e, const Emit& emit) {
  const auto& odo = std::get<Odometry>(e);
  ++processed_;
  const SE3 odom = to_se3(odo.pose);
  const auto known = tracks_.find(odo.source);
  Track t = known == tracks_.end() ? Track{} : known->second;  // the step is taken on a copy, kept only if healthy
  if (known == tracks_.end()) {
    t.map_pose = odom;
    t.covariance = odo.covariance;
  } else {
    if (odo.utime <= t.utime) return;  // intake guarantees increasing utime per source; keep the invariant local too
    const SE3 increment = t.last_odom.between(odom);
    const Matrix6 q = increment_covariance(odo, increment, t.last_odom_covariance, config_.min_increment_variance);
    t.map_pose = t.map_pose * increment;
    t.covariance = propagate(t.covariance, increment, q);
  }
  Eigen::Matrix<double, 7, 1> pose;
  pose << t.map_pose.translation(), t.map_pose.rotation().quaternion().coeffs();
  if (const filter::Health h = filter::estimate_health(pose, t.covariance, 6); h != filter::Health::kHealthy) {
    refusals_.count(h);
    return;
  }
  if (known != tracks_.end() && static_cast<double>(odo.utime - t.utime) * 1e-6 > config_.max_gap_s) ++gaps_;
  t.utime = odo.utime;
  t.last_odom = odom;
  t.last_odom_covariance = odo.covariance;
  tracks_[odo.source] = t;

  FusedPose out;
  out.utime = odo.utime;
  out.source = odo.source;
  out.estimator = estimator();
  out.planar = odo.planar;
  out.pose = to_pose(t.map_pose);
  out.covariance = t.covariance;
  emit(out);
}

Counters DeadReckoningStage::counters() const {
  return {{"odometry_processed", processed_},
          {"odometry_gaps", gaps_},
          {"sources", static_cast<int64_t>(tracks_.size())},
          {"refused_non_finite", refusals_.non_finite},
          {"refused_indefinite", refusals_.indefinite}};
}

void DeadReckoningStage::save(archive::ArchiveWriter& w) {
  w(static_cast<uint64_t>(tracks_.size()));
  for (const auto& [source, t] : tracks_)
    w(source)(t.utime)(t.last_odom)(t.last_odom_covariance)(t.map_pose)(t.covariance);
  w(gaps_)(processed_)(refusals_.non_finite)(refusals_.indefinite);
}

void DeadReckoningStage::load(archive::ArchiveReader& r) {
  tracks_.clear();
  const uint64_t n = r.count(1, "the dead-reckoning tracks");
  for (uint64_t i = 0; i < n; ++i) {
    Track& t = tracks_[r.get<std::string>()];
    r(t.utime)(t.last_odom)(t.last_odom_covariance)(t.map_pose)(t.covariance);
  }
  r(gaps_)(processed_)(refusals_.non_finite)(refusals_.indefinite);
}

}  // namespace sextant::engine
