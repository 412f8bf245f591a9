#include "daemon/engine/filter_stage.hpp"

#include "assoc/chi_square.hpp"
#include "daemon/engine/planar_pose_covariance.hpp"
#include "estimators/lie/planar_axes.hpp"

#include <algorithm>
#include <type_traits>

namespace sextant::engine {
namespace {

constexpr int kPredictRank = 0, kMeasureRank = 1, kSightingsRank = 2;  // order at equal stamps
constexpr size_t kMaxPending = 64;  // sighting batches waiting for the next prediction

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
  const bool has_predictor =
      std::any_of(sources.begin(), sources.end(), [](const auto& kv) { return kv.second.predict; });
  if (!has_predictor && !config_.sources.contains(body))
    sources[body].predict = true;  // the body's own, unlisted source
  const double sxy = config_.initial_sigma_xy, sth = config_.initial_sigma_theta;
  Track t;
  t.fusion = filter::MultiSourceEkf(opt, Eigen::Vector3d(sxy * sxy, sxy * sxy, sth * sth).asDiagonal(),
                                    std::move(sources), config_.min_increment_variance);
  for (const auto& l : config_.map) t.fusion.ekf().set_known_landmark(l.id, {l.x, l.y});
  return t;
}

void FilterStage::recover(const Event& failed) {
  const std::string body = body_of(event_source(failed));
  histories_.erase(body);
  spatial_.erase(body);
}

void FilterStage::handle(const Event& e, const Emit& emit) {
  std::string body;
  int64_t utime = 0;
  int rank = 0;
  bool planar = true;
  Input in;
  if (const auto* o = std::get_if<Odometry>(&e)) {
    body = body_of(o->source), utime = o->utime, planar = o->planar, in = *o;
    rank = predicts(o->source) ? kPredictRank : kMeasureRank;
  } else if (const auto* s = std::get_if<LandmarkSightings>(&e)) {
    body = body_of(s->source), utime = s->utime, planar = s->planar, in = *s;
    rank = kSightingsRank;
    if (!histories_.contains(body) && !spatial_.contains(body)) {
      ++before_odometry_;
      return;
    }
  } else {
    return;
  }
  // A body is planar or 3-D from its first message on.
  if ((planar && spatial_.contains(body)) || (!planar && histories_.contains(body))) {
    ++mixed_;
    return;
  }
  const auto window = static_cast<int64_t>(config_.history_s * 1e6);
  if (planar) {
    auto it = histories_.find(body);
    if (it == histories_.end()) it = histories_.try_emplace(body, window, new_track(body)).first;
    add(it->second, body, utime, rank, std::move(in), emit);
  } else {
    auto it = spatial_.find(body);
    if (it == spatial_.end()) it = spatial_.try_emplace(body, window, new_spatial_track()).first;
    add(it->second, body, utime, rank, std::move(in), emit);
  }
}

template <class H>
void FilterStage::add(H& history, const std::string& body, int64_t utime, int rank, Input in, const Emit& emit) {
  const auto outcome = history.add(utime, rank, std::move(in), [this](auto& t, const Input& x) { apply(t, x); });
  if (outcome == H::Outcome::too_late)
    ++too_late_;
  else if (outcome == H::Outcome::reapplied)
    ++reapplied_;
  const auto& t = history.state();
  if (rank != kPredictRank) return;
  int64_t newest = 0;
  if constexpr (std::is_same_v<H, History>) {
    if (!t.fusion.started()) return;
    newest = t.fusion.utime();
  } else {
    if (!t.fusion.started()) return;
    newest = t.fusion.utime();
  }
  if (newest != utime) return;
  auto [p, first] = published_.try_emplace(body, utime);
  if (first || p->second < utime) {
    p->second = utime;
    publish(body, t, emit);
  }
}

void FilterStage::apply(Track& t, const Input& in) const {
  if (const auto* o = std::get_if<Odometry>(&in))
    apply_odometry(t, *o);
  else
    apply_landmarks(t, std::get<LandmarkSightings>(in));
}

void FilterStage::apply_odometry(Track& t, const Odometry& o) const {
  std::vector<int64_t> stops;
  if (predicts(o.source) && !t.pending.empty() && t.fusion.started()) {
    for (const auto& p : t.pending) stops.push_back(p.utime);
  }
  std::vector<LandmarkSightings> waiting;
  waiting.swap(t.pending);
  const auto outcome =
      t.fusion.odometry(o.source, planar_odometry(o), stops, [&](size_t i) { update_with(t, waiting[i]); });
  // Sightings the prediction did not pass (duplicate stamp, a measurement source) wait for the next one.
  for (auto& p : waiting)
    if (outcome != filter::OdometryOutcome::predicted || p.utime >= o.utime) t.pending.push_back(std::move(p));
  switch (outcome) {
    case filter::OdometryOutcome::predicted:
      ++t.predictions;
      break;
    case filter::OdometryOutcome::duplicate:
      ++t.duplicates;
      break;
    case filter::OdometryOutcome::unknown_source:
      ++t.unknown_sources;
      break;
    default:
      break;  // the fusion counts per source
  }
}

void FilterStage::publish(const std::string& body, const Track& t, const Emit& emit) const {
  const filter::PlanarEkf& ekf = t.fusion.ekf();
  const SE2 pose = ekf.pose();
  FusedPose out;
  out.utime = t.fusion.utime();
  out.source = body;
  out.estimator = estimator();
  out.planar = true;
  const SE3 p3 = pose.to_se3();
  out.pose.position = p3.translation();
  out.pose.orientation = p3.rotation().quaternion();
  out.covariance = planar_covariance_in_body_frame(pose, ekf.pose_covariance());
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
  filter::UpdateBudget budget = ekf.new_update_budget();  // bounded work per batch (PlanarEkfOptions::update_budget)
  for (const auto& ob : s.observations) {
    if (ob.id < 0) {
      unidentified.push_back({ob.range, ob.azimuth, ob.covariance.topLeftCorner<2, 2>()});
      continue;
    }
    if (!budget.spend(ekf.state().size())) {
      ++t.over_budget;
      continue;
    }
    const auto r = ekf.observe(ob.id, ob.range, ob.azimuth, ob.covariance.topLeftCorner<2, 2>());
    if (r.accepted)
      (r.reason == filter::UpdateReason::kNewLandmark ? t.new_landmarks : t.updates)++;
    else if (r.reason == filter::UpdateReason::kGate)
      ++t.gated;
    else if (r.reason == filter::UpdateReason::kUnknownLandmark)
      ++t.unknown;
    else
      ++t.rejected;
  }
  if (!unidentified.empty()) {
    const auto a = ekf.observe_unidentified(unidentified, budget);
    t.associated += a.paired;
    t.gated += a.gated;
    t.tentative += a.tentative;
    t.new_landmarks += a.confirmed;
    t.over_budget += a.over_budget;
    t.exhausted += a.exhausted ? 1 : 0;
  }
}

FilterStage::SpatialTrack FilterStage::new_spatial_track() const {
  filter::SpatialEkfOptions opt;
  opt.gate = assoc::chi2_quantile(3, 0.99);
  opt.slam = config_.slam;
  opt.max_landmarks = config_.max_landmarks;
  const double sxy = config_.initial_sigma_xy, sth = config_.initial_sigma_theta;
  Matrix6 P0 = Matrix6::Zero();
  P0.diagonal() << sxy * sxy, sxy * sxy, sxy * sxy, sth * sth, sth * sth, sth * sth;
  SpatialTrack t;
  t.fusion = filter::SpatialFusion(opt, P0, config_.min_increment_variance);
  return t;
}

void FilterStage::apply(SpatialTrack& t, const Input& in) const {
  if (const auto* s = std::get_if<LandmarkSightings>(&in)) {
    if (!t.fusion.started()) {
      ++t.before_odometry;
    } else if (s->utime <= t.fusion.utime()) {
      update_with(t, *s);
    } else {
      if (t.pending.size() >= kMaxPending) {
        t.pending.erase(t.pending.begin());
        ++t.stale_sightings;
      }
      t.pending.push_back(*s);
    }
    return;
  }
  const auto& o = std::get<Odometry>(in);
  if (!predicts(o.source)) {
    ++t.unfused;
    return;
  }
  filter::SpatialOdometry m;
  m.utime = o.utime;
  m.pose = SE3(o.pose.orientation, o.pose.position);
  m.covariance = o.covariance;
  m.increment_covariance = o.increment_covariance;
  std::vector<int64_t> stops;
  for (const auto& p : t.pending) stops.push_back(p.utime);
  std::vector<LandmarkSightings> waiting;
  waiting.swap(t.pending);
  const auto outcome = t.fusion.odometry(m, stops, [&](size_t i) { update_with(t, waiting[i]); });
  // Sightings the prediction did not pass (a duplicate stamp) wait for the next one.
  for (auto& p : waiting)
    if (outcome != filter::SpatialOdometryOutcome::kPredicted || p.utime >= o.utime) t.pending.push_back(std::move(p));
  if (outcome == filter::SpatialOdometryOutcome::kPredicted)
    ++t.predictions;
  else if (outcome == filter::SpatialOdometryOutcome::kDuplicate)
    ++t.duplicates;
}

void FilterStage::update_with(SpatialTrack& t, const LandmarkSightings& s) const {
  filter::UpdateBudget budget = t.fusion.ekf().new_update_budget();
  for (const auto& ob : s.observations) {
    if (ob.id < 0) {
      ++t.unidentified;
      continue;
    }
    if (!budget.spend(t.fusion.ekf().size())) {
      ++t.over_budget;
      continue;
    }
    const auto r = t.fusion.ekf().observe(ob.id, Eigen::Vector3d(ob.range, ob.azimuth, ob.elevation), ob.covariance);
    if (r.accepted)
      (r.reason == filter::UpdateReason::kNewLandmark ? t.new_landmarks : t.updates)++;
    else if (r.reason == filter::UpdateReason::kGate)
      ++t.gated;
    else
      ++t.rejected;
  }
}

void FilterStage::publish(const std::string& body, const SpatialTrack& t, const Emit& emit) const {
  FusedPose out;
  const filter::SpatialEkf& ekf = t.fusion.ekf();
  out.utime = t.fusion.utime();
  out.source = body;
  out.estimator = estimator();
  out.planar = false;
  out.pose.position = ekf.pose().translation();
  out.pose.orientation = ekf.pose().rotation().quaternion();
  out.covariance = ekf.pose_covariance();  // already the right perturbation [rho, phi]
  emit(out);
}

const filter::SpatialEkf* FilterStage::spatial_ekf(const std::string& body) const {
  auto it = spatial_.find(body);
  return it == spatial_.end() || !it->second.state().fusion.started() ? nullptr : &it->second.state().fusion.ekf();
}

Counters FilterStage::counters() const {
  int64_t predictions = 0, updates = 0, gated = 0, new_landmarks = 0, unknown = 0, rejected = 0, before = 0,
          associated = 0, tentative = 0, duplicates = 0, unknown_sources = 0, stale = 0, over_budget = 0, exhausted = 0;
  std::map<std::string, filter::SourceCounters> sources;
  filter::Refusals refused;
  for (const auto& [body, h] : histories_) {
    const Track& t = h.state();
    refused += t.fusion.ekf().refusals();
    predictions += t.predictions, updates += t.updates, gated += t.gated, new_landmarks += t.new_landmarks;
    unknown += t.unknown, rejected += t.rejected, before += t.before_odometry, associated += t.associated;
    tentative += t.tentative, duplicates += t.duplicates, unknown_sources += t.unknown_sources,
        stale += t.stale_sightings;
    over_budget += t.over_budget, exhausted += t.exhausted;
    for (const auto& [name, c] : t.fusion.counters()) sources[name] = c;
  }
  int64_t unidentified = 0, unfused = 0;
  for (const auto& [body, h] : spatial_) {
    const SpatialTrack& t = h.state();
    refused += t.fusion.ekf().refusals();
    predictions += t.predictions, updates += t.updates, gated += t.gated, new_landmarks += t.new_landmarks;
    rejected += t.rejected, before += t.before_odometry, duplicates += t.duplicates, stale += t.stale_sightings;
    unidentified += t.unidentified, unfused += t.unfused, over_budget += t.over_budget;
  }
  Counters out = {{"predictions", predictions},
                  {"updates", updates},
                  {"gated", gated},
                  {"new_landmarks", new_landmarks},
                  {"unknown_landmarks", unknown},
                  {"rejected", rejected},
                  {"mixed_dimensions", mixed_},
                  {"unidentified_3d", unidentified},
                  {"unfused_3d", unfused},
                  {"landmarks_before_odometry", before_odometry_ + before},
                  {"associated", associated},
                  {"tentative_landmarks", tentative},
                  {"duplicate_stamps", duplicates},
                  {"unknown_sources", unknown_sources},
                  {"sightings_without_prediction", stale},
                  {"too_late", too_late_},
                  {"late_reapplied", reapplied_},
                  {"refused_non_finite", refused.non_finite},
                  {"refused_indefinite", refused.indefinite},
                  {"association_over_budget", over_budget},
                  {"association_budget_exhausted", exhausted}};
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
