#include "daemon/engine/particle_filter_stage.hpp"

#include "daemon/engine/event_archive.hpp"

#include "daemon/engine/planar_pose_covariance.hpp"

namespace sextant::engine {

void ParticleFilterStage::handle(const Event& e, const Emit& emit) {
  if (const auto* o = std::get_if<Odometry>(&e))
    on_odometry(*o, emit);
  else if (const auto* s = std::get_if<LandmarkSightings>(&e))
    on_landmarks(*s);
}

void ParticleFilterStage::on_odometry(const Odometry& o, const Emit& emit) {
  if (!o.planar) {
    ++not_planar_;
    return;
  }
  const SE2 odom = SE2::from_se3(SE3(o.pose.orientation, o.pose.position));
  if (!odom.translation().allFinite() || !std::isfinite(odom.angle())) {
    ++bad_odometry_;
    return;
  }
  auto it = tracks_.find(o.source);
  if (it == tracks_.end()) {
    it = tracks_.emplace(o.source, Track{filter::FastSlam(fastslam_options()), odom, o.covariance, o.utime}).first;
    Track& t = it->second;
    for (const auto& l : config_.map) t.pf.set_known_landmark(l.id, {l.x, l.y});
    const double sxy = config_.initial_sigma_xy, sth = config_.initial_sigma_theta;
    t.pf.initialize(odom, Eigen::Vector3d(sxy * sxy, sxy * sxy, sth * sth).asDiagonal());
  } else {
    Track& t = it->second;
    if (o.utime <= t.utime) {
      ++out_of_order_;
      return;
    }
    const SE2 delta = t.last_odom.between(odom);
    const filter::FastSlam before = t.pf;  // O(particles): the maps are shared, copy-on-write
    if (!t.pf.predict(delta,
                      planar_increment_covariance(o, t.last_covariance, delta, config_.min_increment_variance))) {
      ++bad_odometry_;
      return;
    }
    if (const filter::Health h = t.pf.health(); h != filter::Health::kHealthy) {
      t.pf = before;
      refusals_.count(h);
      return;
    }
    ++predictions_;
    t.last_odom = odom;
    t.last_covariance = o.covariance;
    t.utime = o.utime;
  }
  const Track& t = it->second;
  SE2 pose;
  Eigen::Matrix3d covariance;
  t.pf.mixture(&pose, &covariance);
  FusedPose out;
  out.utime = o.utime;
  out.source = o.source;
  out.estimator = estimator();
  out.planar = true;
  const SE3 p3 = pose.to_se3();
  out.pose.position = p3.translation();
  out.pose.orientation = p3.rotation().quaternion();
  out.covariance = planar_covariance_in_body_frame(pose, covariance);
  emit(out);
}

void ParticleFilterStage::on_landmarks(const LandmarkSightings& s) {
  auto it = tracks_.find(s.source);
  if (it == tracks_.end()) {
    ++before_odometry_;
    return;
  }
  if (!s.planar) {
    ++not_planar_;
    return;
  }
  std::vector<filter::RangeBearing> batch;
  batch.reserve(s.observations.size());
  for (const auto& ob : s.observations)
    batch.push_back({ob.id, ob.range, ob.azimuth, ob.covariance.topLeftCorner<2, 2>()});
  filter::FastSlam& pf = it->second.pf;
  const filter::FastSlam before = pf;
  const auto r = pf.observe(batch);
  if (const filter::Health h = pf.health(); h != filter::Health::kHealthy) {
    pf = before;
    refusals_.count(h);
    return;
  }
  updates_ += r.updated;
  new_landmarks_ += r.created;
  associated_ += r.associated;
  gated_ += r.gated;
  rejected_ += r.rejected;
  unknown_ += r.unknown;
  removed_ += r.removed;
  over_budget_ += r.over_budget;
  resamplings_ += r.resampled;
}

Counters ParticleFilterStage::counters() const {
  return {{"predictions", predictions_},
          {"bad_odometry", bad_odometry_},
          {"out_of_order", out_of_order_},
          {"updates", updates_},
          {"new_landmarks", new_landmarks_},
          {"associated", associated_},
          {"gated", gated_},
          {"rejected", rejected_},
          {"unknown_landmarks", unknown_},
          {"removed_tentative", removed_},
          {"resamplings", resamplings_},
          {"not_planar", not_planar_},
          {"landmarks_before_odometry", before_odometry_},
          {"refused_non_finite", refusals_.non_finite},
          {"refused_indefinite", refusals_.indefinite},
          {"association_over_budget", over_budget_}};
}

std::map<int64_t, Eigen::Vector2d> ParticleFilterStage::landmarks(const std::string& source) const {
  auto it = tracks_.find(source);
  return it == tracks_.end() ? std::map<int64_t, Eigen::Vector2d>{} : it->second.pf.landmarks();
}

const filter::FastSlam* ParticleFilterStage::filter(const std::string& source) const {
  auto it = tracks_.find(source);
  return it == tracks_.end() ? nullptr : &it->second.pf;
}

filter::FastSlamOptions ParticleFilterStage::fastslam_options() const {
  filter::FastSlamOptions opt;
  opt.particles = config_.pf.particles;
  opt.resample_threshold = config_.pf.resample_threshold;
  opt.seed = config_.pf.seed;
  opt.slam = config_.slam;
  opt.gate = config_.gate;
  opt.max_landmarks = config_.max_landmarks;
  opt.confirmations = config_.pf.confirmations;
  opt.tentative_lifetime = config_.pf.tentative_lifetime;
  return opt;
}

void ParticleFilterStage::save(archive::ArchiveWriter& w) {
  w(static_cast<uint64_t>(tracks_.size()));
  for (const auto& [source, t] : tracks_) w(source)(t.pf)(t.last_odom)(t.last_covariance)(t.utime);
  w(predictions_)(bad_odometry_)(
      out_of_order_)(updates_)(new_landmarks_)(associated_)(gated_)(rejected_)(unknown_)(removed_)(resamplings_)(not_planar_)(before_odometry_)(refusals_
                                                                                                                                                    .non_finite)(
      refusals_.indefinite)(over_budget_);
}

void ParticleFilterStage::load(archive::ArchiveReader& r) {
  tracks_.clear();
  const uint64_t n = r.count(1, "the particle filters");
  for (uint64_t i = 0; i < n; ++i) {
    const auto source = r.get<std::string>();
    Track t{filter::FastSlam(fastslam_options()), SE2(), Matrix6::Zero(), 0};
    r(t.pf)(t.last_odom)(t.last_covariance)(t.utime);
    tracks_.emplace(source, std::move(t));
  }
  r(predictions_)(bad_odometry_)(
      out_of_order_)(updates_)(new_landmarks_)(associated_)(gated_)(rejected_)(unknown_)(removed_)(resamplings_)(not_planar_)(before_odometry_)(refusals_
                                                                                                                                                    .non_finite)(
      refusals_.indefinite)(over_budget_);
}

}  // namespace sextant::engine
