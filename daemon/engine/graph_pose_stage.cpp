#include "daemon/engine/graph_pose_stage.hpp"

#include "daemon/engine/event_archive.hpp"

#include "daemon/engine/pose_conversion.hpp"
#include "daemon/engine/pose_covariance.hpp"

namespace sextant::engine {

void GraphPoseStage::handle(const Event& e, const Emit& emit) {
  const auto& o = std::get<Odometry>(e);
  FusedPose out;
  out.utime = o.utime;
  out.source = o.source;
  out.estimator = estimator();
  out.planar = o.planar;
  const SE3 odom = to_se3(o.pose);
  if (const auto c = corrections_->get(o.source)) {
    const SE3 delta = c->keyframe_odom.between(odom);
    // The odometry's own uncertainty growth since the keyframe, PSD without a floor (pose_covariance.hpp says why).
    const Matrix6 growth = nearest_psd(pose_covariance_growth(o.covariance, delta, c->keyframe_odom_covariance));
    out.pose = to_pose(c->keyframe_map * delta);
    out.frame = c->frame;
    record_correction_age(o.utime - c->keyframe_utime);
    out.covariance = compose_covariance(c->keyframe_covariance, delta, growth);
  } else {
    ++before_correction_;
    out.pose = o.pose;
    out.covariance = o.covariance;
  }
  Eigen::Matrix<double, 7, 1> pose;
  pose << out.pose.position, out.pose.orientation.coeffs();
  if (const filter::Health h = filter::estimate_health(pose, out.covariance, 6); h != filter::Health::kHealthy) {
    refusals_.count(h);
    return;
  }
  ++published_;
  emit(out);
}

void GraphPoseStage::save(archive::ArchiveWriter& w) {
  w(published_)(before_correction_)(correction_ages_)(static_cast<uint64_t>(age_next_));
  w(refusals_.non_finite)(refusals_.indefinite);
}

void GraphPoseStage::load(archive::ArchiveReader& r) {
  r(published_)(before_correction_)(correction_ages_);
  age_next_ = static_cast<size_t>(r.get<uint64_t>());
  r(refusals_.non_finite)(refusals_.indefinite);
  // Filling, the next slot is the one after the last (== size); full, any slot of the ring.
  const size_t n = correction_ages_.size();
  if (n > kAgeRing || (n < kAgeRing && age_next_ != n) || (n == kAgeRing && age_next_ >= kAgeRing))
    r.fail("graph_pose: correction ages out of range");
}

}  // namespace sextant::engine
