#include "daemon/engine/filter_stage.hpp"

#include "daemon/engine/dead_reckoning_stage.hpp"
#include "daemon/engine/planar_pose_covariance.hpp"

#include <Eigen/Eigenvalues>

namespace sextant::engine {

void FilterStage::handle(const Event& e, const Emit& emit) {
  if (const auto* o = std::get_if<Odometry>(&e)) on_odometry(*o, emit);
  else if (const auto* s = std::get_if<LandmarkSightings>(&e)) on_landmarks(*s);
}

void FilterStage::on_odometry(const Odometry& o, const Emit& emit) {
  if (!o.planar) {
    ++not_planar_;
    return;
  }
  const SE2 odom = SE2::from_se3(SE3(o.pose.orientation, o.pose.position));
  auto [it, first] = tracks_.try_emplace(o.source);
  Track& t = it->second;
  if (first) {
    filter::PlanarEkfOptions opt;
    opt.gate = config_.gate;
    opt.slam = config_.slam;
    opt.max_landmarks = config_.max_landmarks;
    t.ekf = filter::PlanarEkf(opt);
    for (const auto& l : config_.map) t.ekf.set_known_landmark(l.id, {l.x, l.y});
    const double sxy = config_.initial_sigma_xy, sth = config_.initial_sigma_theta;
    t.ekf.initialize(odom, Eigen::Vector3d(sxy * sxy, sxy * sxy, sth * sth).asDiagonal());
  } else {
    if (o.utime <= t.utime) return;
    const SE2 delta = t.last_odom.between(odom);
    Matrix6 q6;
    if (o.increment_covariance) {
      q6 = *o.increment_covariance;
    } else {  // differential mode, as dead reckoning does it
      q6 = o.covariance - DeadReckoningStage::propagate(t.last_covariance, delta.to_se3(), Matrix6::Zero());
    }
    Eigen::Matrix3d Q;
    const int idx[3] = {0, 1, 5};
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) Q(r, c) = q6(idx[r], idx[c]);
    Q = (0.5 * (Q + Q.transpose())).eval();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(Q);
    Q = eig.eigenvectors() * eig.eigenvalues().cwiseMax(config_.min_increment_variance).asDiagonal() *
        eig.eigenvectors().transpose();
    t.ekf.predict(delta, Q);
    ++predictions_;
  }
  t.last_odom = odom;
  t.last_covariance = o.covariance;
  t.utime = o.utime;

  const SE2 pose = t.ekf.pose();
  FusedPose out;
  out.utime = o.utime;
  out.source = o.source;
  out.estimator = "ekf";
  out.planar = true;
  const SE3 p3 = pose.to_se3();
  out.pose.position = p3.translation();
  out.pose.orientation = p3.rotation().quaternion();
  out.covariance = planar_covariance_in_body_frame(pose, t.ekf.pose_covariance());
  emit(out);
}

void FilterStage::on_landmarks(const LandmarkSightings& s) {
  auto it = tracks_.find(s.source);
  if (it == tracks_.end()) {
    ++before_odometry_;
    return;
  }
  if (!s.planar) {
    ++not_planar_;
    return;
  }
  std::vector<filter::Sighting> unidentified;
  for (const auto& ob : s.observations) {
    if (ob.id < 0) {
      unidentified.push_back({ob.range, ob.azimuth, ob.covariance.topLeftCorner<2, 2>()});
      continue;
    }
    const auto r = it->second.ekf.observe(ob.id, ob.range, ob.azimuth, ob.covariance.topLeftCorner<2, 2>());
    if (r.accepted) (r.reason == "new_landmark" ? new_landmarks_ : updates_)++;
    else if (r.reason == "gate") ++gated_;
    else if (r.reason == "unknown_landmark") ++unknown_;
    else ++rejected_;
  }
  if (!unidentified.empty()) {
    const auto a = it->second.ekf.observe_unidentified(unidentified);
    associated_ += a.paired;
    gated_ += a.gated;
    tentative_ += a.tentative;
    new_landmarks_ += a.confirmed;
  }
}

Counters FilterStage::counters() const {
  return {{"predictions", predictions_},        {"updates", updates_},       {"gated", gated_},
          {"new_landmarks", new_landmarks_},    {"unknown_landmarks", unknown_}, {"rejected", rejected_},
          {"not_planar", not_planar_},          {"landmarks_before_odometry", before_odometry_},
          {"associated", associated_},          {"tentative_landmarks", tentative_}};
}

std::map<int64_t, Eigen::Vector2d> FilterStage::landmarks(const std::string& source) const {
  auto it = tracks_.find(source);
  return it == tracks_.end() ? std::map<int64_t, Eigen::Vector2d>{} : it->second.ekf.landmarks();
}

}  // namespace sextant::engine
