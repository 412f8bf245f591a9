#include "daemon/engine/filter_stage.hpp"

#include <algorithm>

namespace sextant::engine {
namespace {

constexpr int kPredictRank = 0, kMeasureRank = 1, kSightingsRank = 2;  // order at equal stamps
constexpr int kPlanar[3] = {0, 1, 5};                                   // x, y, yaw in sextant's 6-D tangent order
constexpr size_t kMaxPending = 64;  // sighting batches waiting for the next prediction

Eigen::Matrix3d planar_block(const Matrix6& m) {
  Eigen::Matrix3d out;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out(r, c) = m(kPlanar[r], kPlanar[c]);
  return out;
}

filter::PlanarOdometry planar_odometry(const Odometry& o) {
  filter::PlanarOdometry m;
  m.utime = o.utime;
  m.pose = SE2::from_se3(SE3(o.pose.orientation, o.pose.position));
  m.covariance = planar_block(o.covariance);
  if (o.increment_covariance) m.increment_covariance = planar_block(*o.increment_covariance);
  if (o.twist) {
    m.twist = Eigen::Vector3d(o.twist->linear.x(), o.twist->linear.y(), o.twist->angular.z());
    m.twist_covariance = planar_block(o.twist->covariance);
  }
  return m;
}

}  // namespace

std::string FilterStage::body_of(const std::string& source) const {
  auto it = config_.sources.find(source);
  return it == config_.sources.end() || it->second.body.empty() ? source : it->second.body;
}

bool FilterStage::predicts(const std::string& source) const {
  auto it = config_.sources.find(source);
  return it == config_.sources.end() || it->second.predict;  // unlisted: a body of its own, or its body's predictor
}

FilterStage::Track FilterStage::new_track(const std::string& body) const {
  filter::PlanarEkfOptions opt;
  opt.gate = config_.gate;
  opt.slam = config_.slam;
  opt.max_landmarks = config_.max_landmarks;
  std::map<std::string, filter::OdometrySourceOptions> sources;
  for (const auto& [name, s] : config_.sources)
    if (body_of(name) == body) sources[name] = {s.predict, s.fuse, s.differential, s.gate, s.timeout_s};
  const bool has_predictor = std::any_of(sources.begin(), sources.end(), [](const auto& kv) { return kv.second.predict; });
  if (!has_predictor && !config_.sources.contains(body)) sources[body].predict = true;  // the body's own, unlisted source
  const double sxy = config_.initial_sigma_xy, sth = config_.initial_sigma_theta;
  Track t;
  t.fusion = filter::MultiSourceEkf(opt, Eigen::Vector3d(sxy * sxy, sxy * sxy, sth * sth).asDiagonal(), std::move(sources),
                                    config_.min_increment_variance);
  for (const auto& l : config_.map) t.fusion.ekf().set_known_landmark(l.id, {l.x, l.y});
  return t;
}

void FilterStage::handle(const Event& e, const Emit& emit) {
  std::string body;
  int64_t utime = 0;
  int rank = 0;
  Input in;
  if (const auto* o = std::get_if<Odometry>(&e)) {
    if (!o->planar) {
      ++not_planar_;
      return;
    }
    body = body_of(o->source), utime = o->utime, rank = predicts(o->source) ? kPredictRank : kMeasureRank, in = *o;
  } else if (const auto* s = std::get_if<LandmarkSightings>(&e)) {
    if (!s->planar) {
      ++not_planar_;
      return;
    }
    body = body_of(s->source), utime = s->utime, rank = kSightingsRank, in = *s;
    if (!histories_.contains(body)) {
      ++before_odometry_;
      return;
    }
  } else {
    return;
  }
  auto it = histories_.find(body);
  if (it == histories_.end()) it = histories_.try_emplace(body, static_cast<int64_t>(config_.history_s * 1e6), new_track(body)).first;
  const auto outcome = it->second.add(utime, rank, std::move(in), [this](Track& t, const Input& x) { apply(t, x); });
  if (outcome == History::Outcome::too_late) ++too_late_;
  else if (outcome == History::Outcome::reapplied) ++reapplied_;
  const Track& t = it->second.state();
  if (rank == kPredictRank && t.fusion.started() && t.fusion.utime() == utime) {
    auto [p, first] = published_.try_emplace(body, utime);
    if (first || p->second < utime) {
      p->second = utime;
      publish(body, t, emit);
    }
  }
}

void FilterStage::apply(Track& t, const Input& in) const {
  if (const auto* o = std::get_if<Odometry>(&in)) apply_odometry(t, *o);
  else apply_landmarks(t, std::get<LandmarkSightings>(in));
}

void FilterStage::apply_odometry(Track& t, const Odometry& o) const {
  std::vector<int64_t> stops;
  if (predicts(o.source) && !t.pending.empty() && t.fusion.started()) {
    for (const auto& p : t.pending) stops.push_back(p.utime);
  }
  std::vector<LandmarkSightings> waiting;
  waiting.swap(t.pending);
  const auto outcome = t.fusion.odometry(o.source, planar_odometry(o), stops, [&](size_t i) { update_with(t, waiting[i]); });
  // Sightings the prediction did not pass (duplicate stamp, a measurement source) wait for the next one.
  for (auto& p : waiting)
    if (outcome != filter::OdometryOutcome::predicted || p.utime >= o.utime) t.pending.push_back(std::move(p));
  switch (outcome) {
    case filter::OdometryOutcome::predicted: ++t.predictions; break;
    case filter::OdometryOutcome::duplicate: ++t.duplicates; break;
    case filter::OdometryOutcome::unknown_source: ++t.unknown_sources; break;
    default: break;  // the fusion counts per source
  }
}

void FilterStage::publish(const std::string& body, const Track& t, const Emit& emit) const {
  const filter::PlanarEkf& ekf = t.fusion.ekf();
  const SE2 pose = ekf.pose();
  FusedPose out;
  out.utime = t.fusion.utime();
  out.source = body;
  out.estimator = "ekf";
  out.planar = true;
  const SE3 p3 = pose.to_se3();
  out.pose.position = p3.translation();
  out.pose.orientation = p3.rotation().quaternion();
  // (x, y, theta) covariance -> right perturbation in the body frame: delta_body = blockdiag(R^T, 1) delta_global.
  Eigen::Matrix3d J = Eigen::Matrix3d::Identity();
  J.topLeftCorner<2, 2>() = pose.rotation().matrix().transpose();
  const Eigen::Matrix3d Pb = J * ekf.pose_covariance() * J.transpose();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out.covariance(kPlanar[r], kPlanar[c]) = Pb(r, c);
  emit(out);
}

void FilterStage::apply_landmarks(Track& t, const LandmarkSightings& s) const {
  t.fusion.advance(s.utime);
  if (!t.fusion.started()) {
    ++t.before_odometry;
    return;
  }
  if (s.utime <= t.fusion.utime()) {
    update_with(t, s);
    return;
  }
  if (t.pending.size() >= kMaxPending) {  // the predicting source is silent: do not hoard
    t.pending.erase(t.pending.begin());
    ++t.stale_sightings;
  }
  t.pending.push_back(s);
}

void FilterStage::update_with(Track& t, const LandmarkSightings& s) const {
  filter::PlanarEkf& ekf = t.fusion.ekf();
  std::vector<filter::Sighting> unidentified;
  for (const auto& ob : s.observations) {
    if (ob.id < 0) {
      unidentified.push_back({ob.range, ob.azimuth, ob.covariance.topLeftCorner<2, 2>()});
      continue;
    }
    const auto r = ekf.observe(ob.id, ob.range, ob.azimuth, ob.covariance.topLeftCorner<2, 2>());
    if (r.accepted) (r.reason == "new_landmark" ? t.new_landmarks : t.updates)++;
    else if (r.reason == "gate") ++t.gated;
    else if (r.reason == "unknown_landmark") ++t.unknown;
    else ++t.rejected;
  }
  if (!unidentified.empty()) {
    const auto a = ekf.observe_unidentified(unidentified);
    t.associated += a.paired;
    t.gated += a.gated;
    t.tentative += a.tentative;
    t.new_landmarks += a.confirmed;
  }
}

Counters FilterStage::counters() const {
  int64_t predictions = 0, updates = 0, gated = 0, new_landmarks = 0, unknown = 0, rejected = 0, before = 0, associated = 0,
          tentative = 0, duplicates = 0, unknown_sources = 0, stale = 0;
  std::map<std::string, filter::SourceCounters> sources;
  for (const auto& [body, h] : histories_) {
    const Track& t = h.state();
    predictions += t.predictions, updates += t.updates, gated += t.gated, new_landmarks += t.new_landmarks;
    unknown += t.unknown, rejected += t.rejected, before += t.before_odometry, associated += t.associated;
    tentative += t.tentative, duplicates += t.duplicates, unknown_sources += t.unknown_sources, stale += t.stale_sightings;
    for (const auto& [name, c] : t.fusion.counters()) sources[name] = c;
  }
  Counters out = {{"predictions", predictions},
                  {"updates", updates},
                  {"gated", gated},
                  {"new_landmarks", new_landmarks},
                  {"unknown_landmarks", unknown},
                  {"rejected", rejected},
                  {"not_planar", not_planar_},
                  {"landmarks_before_odometry", before_odometry_ + before},
                  {"associated", associated},
                  {"tentative_landmarks", tentative},
                  {"duplicate_stamps", duplicates},
                  {"unknown_sources", unknown_sources},
                  {"sightings_without_prediction", stale},
                  {"too_late", too_late_},
                  {"late_reapplied", reapplied_}};
  // Per configured source (the measurement sources of multi-source bodies): fused, gated, rejected, timeouts, and
  // whether it is silent now.
  for (const auto& [name, cfg] : config_.sources) {
    auto it = sources.find(name);
    if (it == sources.end()) continue;
    const auto& c = it->second;
    out.push_back({"source." + name + ".fused", c.fused});
    out.push_back({"source." + name + ".gated", c.gated});
    out.push_back({"source." + name + ".rejected", c.rejected});
    out.push_back({"source." + name + ".timeouts", c.timeouts});
    out.push_back({"source." + name + ".silent", c.silent ? 1 : 0});
  }
  return out;
}

std::map<int64_t, Eigen::Vector2d> FilterStage::landmarks(const std::string& body) const {
  const auto* e = ekf(body);
  return e == nullptr ? std::map<int64_t, Eigen::Vector2d>{} : e->landmarks();
}

const filter::PlanarEkf* FilterStage::ekf(const std::string& body) const {
  auto it = histories_.find(body);
  return it == histories_.end() || !it->second.state().fusion.started() ? nullptr : &it->second.state().fusion.ekf();
}

}  // namespace sextant::engine
