#include "daemon/engine/filter_stage.hpp"

#include "daemon/engine/dead_reckoning_stage.hpp"

#include <Eigen/Eigenvalues>

namespace sextant::engine {
namespace {

constexpr int kOdometryRank = 0, kSightingsRank = 1;  // equal stamps: predict first, then update

}  // namespace

void FilterStage::handle(const Event& e, const Emit& emit) {
  const std::string* source = nullptr;
  int64_t utime = 0;
  int rank = 0;
  Input in;
  if (const auto* o = std::get_if<Odometry>(&e)) {
    if (!o->planar) {
      ++not_planar_;
      return;
    }
    source = &o->source, utime = o->utime, rank = kOdometryRank, in = *o;
  } else if (const auto* s = std::get_if<LandmarkSightings>(&e)) {
    if (!s->planar) {
      ++not_planar_;
      return;
    }
    if (!histories_.contains(s->source)) {
      ++before_odometry_;
      return;
    }
    source = &s->source, utime = s->utime, rank = kSightingsRank, in = *s;
  } else {
    return;
  }
  auto it = histories_.find(*source);
  if (it == histories_.end())
    it = histories_.try_emplace(*source, static_cast<int64_t>(config_.history_s * 1e6), Track()).first;
  const auto outcome = it->second.add(utime, rank, std::move(in), [this](Track& t, const Input& x) { apply(t, x); });
  if (outcome == History::Outcome::too_late) ++too_late_;
  else if (outcome == History::Outcome::reapplied) ++reapplied_;
  const Track& t = it->second.state();
  if (rank == kOdometryRank && t.started && t.utime == utime) {
    auto [p, first] = published_.try_emplace(*source, utime);
    if (first || p->second < utime) {
      p->second = utime;
      publish(*source, t, emit);
    }
  }
}

void FilterStage::apply(Track& t, const Input& in) const {
  if (const auto* o = std::get_if<Odometry>(&in)) apply_odometry(t, *o);
  else apply_landmarks(t, std::get<LandmarkSightings>(in));
}

void FilterStage::apply_odometry(Track& t, const Odometry& o) const {
  const SE2 odom = SE2::from_se3(SE3(o.pose.orientation, o.pose.position));
  if (!t.started) {
    filter::PlanarEkfOptions opt;
    opt.gate = config_.gate;
    opt.slam = config_.slam;
    opt.max_landmarks = config_.max_landmarks;
    t.ekf = filter::PlanarEkf(opt);
    for (const auto& l : config_.map) t.ekf.set_known_landmark(l.id, {l.x, l.y});
    const double sxy = config_.initial_sigma_xy, sth = config_.initial_sigma_theta;
    t.ekf.initialize(odom, Eigen::Vector3d(sxy * sxy, sxy * sxy, sth * sth).asDiagonal());
    t.started = true;
  } else {
    if (o.utime <= t.utime) {  // inputs come in utime order: only an equal stamp gets here
      ++t.duplicates;
      return;
    }
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
    ++t.predictions;
  }
  t.last_odom = odom;
  t.last_covariance = o.covariance;
  t.utime = o.utime;
}

void FilterStage::publish(const std::string& source, const Track& t, const Emit& emit) const {
  const SE2 pose = t.ekf.pose();
  FusedPose out;
  out.utime = t.utime;
  out.source = source;
  out.estimator = "ekf";
  out.planar = true;
  const SE3 p3 = pose.to_se3();
  out.pose.position = p3.translation();
  out.pose.orientation = p3.rotation().quaternion();
  // (x, y, theta) covariance -> right perturbation in the body frame: delta_body = blockdiag(R^T, 1) delta_global.
  Eigen::Matrix3d J = Eigen::Matrix3d::Identity();
  J.topLeftCorner<2, 2>() = pose.rotation().matrix().transpose();
  const Eigen::Matrix3d Pb = J * t.ekf.pose_covariance() * J.transpose();
  const int idx[3] = {0, 1, 5};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out.covariance(idx[r], idx[c]) = Pb(r, c);
  emit(out);
}

void FilterStage::apply_landmarks(Track& t, const LandmarkSightings& s) const {
  if (!t.started) {
    ++t.before_odometry;
    return;
  }
  std::vector<filter::Sighting> unidentified;
  for (const auto& ob : s.observations) {
    if (ob.id < 0) {
      unidentified.push_back({ob.range, ob.azimuth, ob.covariance.topLeftCorner<2, 2>()});
      continue;
    }
    const auto r = t.ekf.observe(ob.id, ob.range, ob.azimuth, ob.covariance.topLeftCorner<2, 2>());
    if (r.accepted) (r.reason == "new_landmark" ? t.new_landmarks : t.updates)++;
    else if (r.reason == "gate") ++t.gated;
    else if (r.reason == "unknown_landmark") ++t.unknown;
    else ++t.rejected;
  }
  if (!unidentified.empty()) {
    const auto a = t.ekf.observe_unidentified(unidentified);
    t.associated += a.paired;
    t.gated += a.gated;
    t.tentative += a.tentative;
    t.new_landmarks += a.confirmed;
  }
}

Counters FilterStage::counters() const {
  Track sum;
  for (const auto& [source, h] : histories_) {
    const Track& t = h.state();
    sum.predictions += t.predictions, sum.updates += t.updates, sum.gated += t.gated;
    sum.new_landmarks += t.new_landmarks, sum.unknown += t.unknown, sum.rejected += t.rejected;
    sum.before_odometry += t.before_odometry, sum.associated += t.associated, sum.tentative += t.tentative;
    sum.duplicates += t.duplicates;
  }
  return {{"predictions", sum.predictions},
          {"updates", sum.updates},
          {"gated", sum.gated},
          {"new_landmarks", sum.new_landmarks},
          {"unknown_landmarks", sum.unknown},
          {"rejected", sum.rejected},
          {"not_planar", not_planar_},
          {"landmarks_before_odometry", before_odometry_ + sum.before_odometry},
          {"associated", sum.associated},
          {"tentative_landmarks", sum.tentative},
          {"duplicate_stamps", sum.duplicates},
          {"too_late", too_late_},
          {"late_reapplied", reapplied_}};
}

std::map<int64_t, Eigen::Vector2d> FilterStage::landmarks(const std::string& source) const {
  const auto* e = ekf(source);
  return e == nullptr ? std::map<int64_t, Eigen::Vector2d>{} : e->landmarks();
}

const filter::PlanarEkf* FilterStage::ekf(const std::string& source) const {
  auto it = histories_.find(source);
  return it == histories_.end() || !it->second.state().started ? nullptr : &it->second.state().ekf;
}

}  // namespace sextant::engine
