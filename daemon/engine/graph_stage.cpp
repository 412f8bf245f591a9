#include "daemon/engine/graph_stage.hpp"

#include "daemon/engine/event_archive.hpp"
#include "daemon/engine/pose_conversion.hpp"
#include "estimators/filter/estimate_health.hpp"

namespace sextant::engine {
namespace {

slam::OdometryInput to_input(const Odometry& o) {
  return {o.utime, o.planar, to_se3(o.pose), o.covariance, o.increment_covariance};
}

slam::LoopInput to_input(const LoopClosure& l) {
  return {l.utime_from, l.utime_to, l.keyframe_from, l.keyframe_to, to_se3(l.relative), l.information, l.source_to};
}

slam::SightingsInput to_input(const LandmarkSightings& s) {
  slam::SightingsInput in{s.utime, s.planar, to_se3(s.sensor_in_body), {}};
  in.sightings.reserve(s.observations.size());
  for (const LandmarkObservation& o : s.observations)
    in.sightings.push_back({o.id, o.range, o.azimuth, o.elevation, o.covariance});
  return in;
}

Keyframe to_keyframe(const slam::KeyframeEstimate& k) { return Keyframe{k.id, k.utime, to_pose(k.pose)}; }

// The layer's options with the stage's interrupt flag in every smoother's options.
slam::SlamOptions interruptible(const GraphConfig& config, const std::atomic<bool>& flag) {
  slam::SlamOptions o = config;
  o.smoother.interrupt = &flag;
  return o;
}

}  // namespace

/// The layer's reports during one handle() call, as outputs: MATCH_REQUESTS, TRAJECTORY and the correction.
class GraphStage::Outputs final : public slam::SlamListener {
 public:
  Outputs(GraphStage& stage, const Emit& emit) : stage_(stage), emit_(emit) {}

  void updated(const std::string& body, int64_t utime, const graph::IncrementalStatus& status) override {
    Feed& f = stage_.feed_of(body);
    f.newest_utime = utime;
    if (f.feed.due(utime)) stage_.publish_trajectory(body, f, utime, status.solves, false, emit_);
    stage_.publish_map(stage_.slam_.frame_of(body), utime, false, emit_);
    // A remote body (its graph built from another daemon's contributions) has its trajectory here, this daemon's
    // view of it; its fused pose comes from the daemon that has its odometry.
    if (stage_.slam_.remote(body)) return;
    // While a thinned graph's factorization is being built over a few updates nothing is solved: the standing
    // correction is still this graph's (a new keyframe's estimate is the one before it composed with its odometry).
    if (status.building) return;
    const slam::SlamGraph::NewestKeyframe newest = stage_.slam_.newest_keyframe(body);
    GraphCorrection c;
    c.keyframe_utime = newest.keyframe->utime;
    c.keyframe_odom = newest.keyframe->odom;
    c.keyframe_map = newest.estimate;
    c.keyframe_covariance = newest.covariance;
    c.keyframe_odom_covariance = newest.keyframe->odom_covariance;
    c.frame = stage_.slam_.frame_of(body);
    // A solve gone wrong never reaches FUSED_POSE: the previous correction stays.
    Eigen::Matrix<double, 7, 1> pose;
    pose << c.keyframe_map.translation(), c.keyframe_map.rotation().quaternion().coeffs();
    if (filter::estimate_health(pose, c.keyframe_covariance, 6) != filter::Health::kHealthy) {
      ++stage_.counters_.corrections_refused;
      return;
    }
    stage_.corrections_->set(body, c);
  }

  void loop_proposed(const std::string& body, int64_t utime, const slam::KeyframeEstimate& a,
                     const slam::KeyframeEstimate& b, bool random) override {
    request(body, utime, random ? "random" : "local", a, body, b);
  }

  void fleet_loop_proposed(const std::string& body, int64_t utime, const slam::KeyframeEstimate& a,
                           const std::string& other, const slam::KeyframeEstimate& b) override {
    request(body, utime, "fleet", a, other, b);
  }

  void contributed(const slam::GraphContribution& c) override {
    if (stage_.exchange_) stage_.exchange_->contributed(c);
  }

 private:
  /// A MATCH_REQUESTS message: keyframe `a` of `body` against keyframe `b` of `body_b`, numbered here.
  void request(const std::string& body, int64_t utime, const char* kind, const slam::KeyframeEstimate& a,
               const std::string& body_b, const slam::KeyframeEstimate& b) {
    MatchRequest r;
    r.utime = utime;
    r.source = body;
    r.request_id = stage_.next_request_id_++;
    r.kind = kind;
    r.source_b = body_b;
    r.a = to_keyframe(a);
    r.b = to_keyframe(b);
    ++stage_.counters_.match_requests;
    emit_(r);
  }

  GraphStage& stage_;
  const Emit& emit_;
};

GraphStage::GraphStage(const GraphConfig& config, std::shared_ptr<GraphCorrectionBoard> corrections)
    : config_(config), corrections_(std::move(corrections)), slam_(interruptible(config, interrupt_)) {
  if (config_.fleet_exchange.enabled) exchange_ = std::make_unique<fleet::FleetExchange>(config_.fleet_exchange);
}

GraphStage::Feed& GraphStage::feed_of(const std::string& source) {
  auto it = feeds_.find(source);
  if (it == feeds_.end()) it = feeds_.emplace(source, Feed{TrajectoryFeed(config_.trajectory), 0}).first;
  return it->second;
}

void GraphStage::handle(const Event& e, const Emit& emit) {
  Outputs out(*this, emit);
  if (exchange_ && exchange_->fetching() && held_back(e)) {
    held_.push_back(e);
    if (held_.size() >= kMaxHeldBack) exchange_->tail.stop();
    exchange_now_ = std::max(exchange_now_, event_utime(e));
    exchange(FleetControl{}, out, emit);  // the clock moved: the wait may end
    return;
  }
  if (const auto* o = std::get_if<Odometry>(&e))
    slam_.add_odometry(o->source, to_input(*o), out);
  else if (const auto* l = std::get_if<LoopClosure>(&e))
    slam_.add_loop(l->source, to_input(*l), out);
  else if (const auto* s = std::get_if<LandmarkSightings>(&e))
    slam_.add_sightings(s->source, to_input(*s), out);
  if (exchange_) exchange(e, out, emit);
}

void GraphStage::exchange(const Event& e, Outputs& out, const Emit& emit) {
  exchange_now_ = std::max(exchange_now_, event_utime(e));
  fleet::FleetExchange::Received r;
  if (const auto* m = std::get_if<FleetContributions>(&e)) r = exchange_->received(*m, exchange_now_);
  // A FleetControl without a sender is the daemon's tick (EngineDriver::tick, never from the wire: the codec refuses
  // an empty sender): only the clock moves, so that heartbeats and repairs go on while no data arrives.
  if (const auto* c = std::get_if<FleetControl>(&e); c && !c->sender.empty())
    r = exchange_->received(*c, exchange_now_);
  for (const slam::GraphContribution& c : r.own) slam_.adopt(c, out);
  slam_.apply_all(r.apply, out);
  for (FleetContributions& a : r.answers) emit(std::move(a));
  fleet::FleetExchange::Due due = exchange_->due(exchange_now_);
  for (const slam::GraphContribution& c : due.own) slam_.adopt(c, out);
  for (FleetContributions& m : due.contributions) emit(std::move(m));
  for (FleetControl& c : due.control) emit(std::move(c));
  if (!exchange_->fetching()) release_held(emit);
}

bool GraphStage::held_back(const Event& e) const {
  // What the wait needs goes through: the tails' answers, the ticks, and the others' requests (answered from the
  // logs, not the graph).  Everything else may make a contribution of a local body (its inputs, and the others'
  // contributions that a local body completes).
  if (const auto* m = std::get_if<FleetContributions>(&e)) return !(m->repair && exchange_->outbox.owns(m->body));
  if (const auto* c = std::get_if<FleetControl>(&e))
    return !c->sender.empty() && c->kind != FleetControl::Kind::kRepair;
  return true;
}

void GraphStage::release_held(const Emit& emit) {
  std::vector<Event> held = std::move(held_);
  held_.clear();
  for (const Event& e : held) handle(e, emit);
}

void GraphStage::publish_trajectory(const std::string& source, Feed& f, int64_t utime, int solves, bool flush,
                                    const Emit& emit) {
  Trajectory header;
  header.source = source;
  header.frame = slam_.frame_of(source);
  header.chi2 = chi2_of(source, utime, flush);
  header.iterations = solves;
  header.solve_ms = slam_.counters().last_update_ms;
  for (auto& t : f.feed.publish(utime, keyframes(source), header, flush)) {
    counters_.trajectory_keyframe_bytes +=
        static_cast<int64_t>(t.keyframes.size()) * 72 + static_cast<int64_t>(t.removed_ids.size()) * 8;
    ++counters_.trajectory_messages;
    emit(std::move(t));
  }
}

double GraphStage::chi2_of(const std::string& source, int64_t utime, bool flush) {
  // Evaluating chi2 touches every factor a solve moved: once per trajectory period for all the bodies of a smoother,
  // not once per body (a fleet of N bodies would pay it N times per period).
  const auto period = static_cast<int64_t>(config_.trajectory.rate_hz > 0 ? 1e6 / config_.trajectory.rate_hz : 0);
  auto& [at, value] = chi2_[slam_.planar(source) ? 1 : 0];
  if (flush || !at || utime - *at >= period || utime < *at) {
    at = utime;
    value = slam_.chi2(source);
  }
  return value;
}

void GraphStage::publish_map(const std::string& frame, int64_t utime, bool flush, const Emit& emit) {
  const auto period = static_cast<int64_t>(config_.trajectory.rate_hz > 0 ? 1e6 / config_.trajectory.rate_hz : 0);
  auto [at, first] = maps_published_.try_emplace(frame, utime);
  if (!flush && !first && utime - at->second < period) return;
  at->second = utime;
  const auto frames = slam_.frames();  // only when due: this runs after every graph update
  const auto send = [&](LandmarkMap m) {
    ++counters_.landmark_map_messages;
    emit(std::move(m));
  };
  for (auto gone = maps_published_.begin(); gone != maps_published_.end();) {  // joined another frame since
    if (frames.contains(gone->first)) {
      ++gone;
      continue;
    }
    send(LandmarkMap{utime, gone->first, {}, 0, 1, 0, {}});
    gone = maps_published_.erase(gone);
  }
  const std::vector<GraphLandmark> landmarks = slam_.landmarks(frame);
  if (landmarks.empty() || !frames.contains(frame)) return;
  LandmarkMap m{utime, frame, frames.at(frame), 0, 0, static_cast<int>(landmarks.size()), {}};
  m.num_chunks = static_cast<int>((landmarks.size() + kMaxLandmarksPerMessage - 1) / kMaxLandmarksPerMessage);
  for (size_t k = 0; k < landmarks.size(); ++k) {
    m.landmarks.push_back({landmarks[k].id, landmarks[k].position, static_cast<int32_t>(landmarks[k].sightings)});
    if (m.landmarks.size() == kMaxLandmarksPerMessage || k + 1 == landmarks.size()) {
      send(m);
      m.landmarks.clear();
      ++m.chunk;
    }
  }
}

void GraphStage::finish(const Emit& emit) {
  Outputs out(*this, emit);
  if (exchange_ && exchange_->fetching()) {  // stopped while waiting for the tails: the inputs held back are not lost
    exchange_->tail.stop();
    exchange(FleetControl{}, out, emit);
  }
  slam_.flush(out);  // the updates the solve period holds back: the final estimates are solved ones
  for (const std::string& source : slam_.bodies()) {
    const slam::KeyframeTrack* track = slam_.track(source);
    if (track->empty()) continue;
    Feed& f = feed_of(source);
    publish_trajectory(source, f, f.newest_utime, 0, true, emit);
  }
  for (const auto& [frame, bodies] : slam_.frames()) {
    int64_t newest = 0;
    for (const std::string& b : bodies) newest = std::max(newest, feed_of(b).newest_utime);
    publish_map(frame, newest, true, emit);
  }
}

int64_t GraphStage::solves_interrupted() const {
  int64_t n = 0;
  for (bool planar : {false, true})
    if (const graph::IncrementalSmoother* s = slam_.smoother(planar)) n += s->interrupted_rebuilds();
  return n;
}

std::vector<Keyframe> GraphStage::keyframes(const std::string& source) const {
  std::vector<Keyframe> out;
  for (const slam::KeyframeEstimate& k : slam_.keyframes(source)) out.push_back(to_keyframe(k));
  return out;
}

Counters GraphStage::counters() const {
  const slam::SlamCounters& s = slam_.counters();
  Counters c{{"updates", s.updates},
             {"keyframes", s.keyframes},
             {"keyframes_rejected", s.keyframes_rejected},
             {"keyframes_reanchored", s.keyframes_reanchored},
             {"match_requests", counters_.match_requests},
             {"loops_accepted", s.loops_accepted},
             {"loops_rejected", s.loops_rejected},
             {"loops_unmatched", s.loops_unmatched},
             {"loops_unknown_source", s.loops_unknown_source},
             {"loops_waiting", s.loops_waiting},
             {"loops_waiting_dropped", s.loops_waiting_dropped},
             {"optimizer_failures", s.optimizer_failures},
             {"rebuilds", s.rebuilds},
             {"relinearized_factors", s.relinearized_factors},
             {"odometry_out_of_order", s.odometry_out_of_order},
             {"odometry_edges_rejected", s.odometry_edges_rejected},
             {"landmarks", s.landmarks},
             {"sightings_accepted", s.sightings_accepted},
             {"sightings_rejected", s.sightings_rejected},
             {"sightings_without_id", s.sightings_without_id},
             {"sightings_unknown_source", s.sightings_unknown_source},
             {"sightings_before_keyframe", s.sightings_before_keyframe},
             {"sightings_unmatched", s.sightings_unmatched},
             {"sightings_malformed", s.sightings_malformed},
             {"sightings_dropped", s.sightings_dropped},
             {"last_update_us", static_cast<int64_t>(s.last_update_ms * 1000)},
             {"trajectory_messages", counters_.trajectory_messages},
             {"thinnings", s.thinnings},
             {"thinning_failures", s.thinning_failures},
             {"keyframes_thinned", s.keyframes_thinned},
             {"loops_thinned", s.loops_thinned},
             {"sightings_thinned", s.sightings_thinned},
             {"landmarks_thinned", s.landmarks_thinned},
             {"loops_on_thinned_keyframes", s.loops_on_thinned},
             {"thinning_us_last", s.thinning_us_last},
             {"thinning_us_max", s.thinning_us_max},
             {"thinning_solve_us_last", s.thinning_solve_us_last},
             {"graph_keyframes", graph_keyframes()},
             {"graph_landmarks", graph_landmarks()},
             {"graph_factors", graph_factors()},
             {"trajectory_keyframe_bytes", counters_.trajectory_keyframe_bytes},
             {"corrections_refused", counters_.corrections_refused},
             {"fleet_frames", static_cast<int64_t>(slam_.frames().size())},
             {"fleet_joins", s.fleet_joins},
             {"fleet_joins_remote", s.fleet_joins_remote},
             {"fleet_joins_refused", s.fleet_joins_refused},
             {"fleet_sightings", s.fleet_sightings},
             {"fleet_loops", s.fleet_loops},
             {"fleet_pending", s.fleet_pending},
             {"fleet_outliers", s.fleet_outliers},
             {"fleet_pending_dropped", s.fleet_pending_dropped},
             {"fleet_sightings_unplaced", s.fleet_sightings_unplaced},
             {"fleet_self_sightings", s.fleet_self_sightings},
             {"fleet_contributions_applied", s.fleet_contributions_applied},
             {"fleet_contributions_refused", s.fleet_contributions_refused},
             {"fleet_contributions_waiting", s.fleet_contributions_waiting},
             {"fleet_contributions_dropped", s.fleet_contributions_dropped},
             {"fleet_remote_inputs", s.fleet_remote_inputs},
             {"landmark_map_messages", counters_.landmark_map_messages},
             {"solves_interrupted", solves_interrupted()}};
  if (exchange_)
    for (auto& [name, value] : exchange_->counters()) c.emplace_back(name, value);
  return c;
}

void GraphStage::save(archive::ArchiveWriter& w) {
  w(next_request_id_)(counters_.match_requests)(counters_.trajectory_messages)(counters_.trajectory_keyframe_bytes)(
      counters_.corrections_refused)(chi2_[0])(chi2_[1]);
  slam_.save(w);
  for (const std::string& source : slam_.bodies()) {
    const Feed& f = feed_of(source);
    w(f.feed)(f.newest_utime)(corrections_->get(source));
  }
  w(exchange_ != nullptr)(exchange_now_);
  if (exchange_) exchange_->save(w);
}

void GraphStage::load(archive::ArchiveReader& r) {
  if (!feeds_.empty()) throw std::logic_error("GraphStage::load into a used stage");
  r(next_request_id_)(counters_.match_requests)(counters_.trajectory_messages)(counters_.trajectory_keyframe_bytes)(
      counters_.corrections_refused)(chi2_[0])(chi2_[1]);
  slam_.load(r);
  for (const std::string& source : slam_.bodies()) {
    Feed& f = feed_of(source);
    r(f.feed)(f.newest_utime);
    if (const auto c = r.get<std::optional<GraphCorrection>>()) corrections_->set(source, *c);
  }
  // The exchange's numbering and streams as they were; a state saved with the exchange off or on loads either way
  // (a daemon that turned it off drops what was saved of it; one that turned it on starts its streams afresh).
  const bool saved_exchange = r.get<bool>();
  r(exchange_now_);
  if (saved_exchange) {
    fleet::FleetExchange saved(config_.fleet_exchange);
    saved.load(r);
    if (exchange_) {
      *exchange_ = std::move(saved);
      exchange_->set_wire_check(wire_check_);
    }
  }
}

void GraphStage::set_fleet_wire_check(fleet::Outbox::WireCheck check) {
  wire_check_ = std::move(check);
  if (exchange_) exchange_->set_wire_check(wire_check_);
}

void GraphStage::forget(const std::string& source) {
  if (!slam_.track(source)) return;
  slam_.forget(source);
  corrections_->erase(source);
  feeds_.erase(source);
}

}  // namespace sextant::engine
