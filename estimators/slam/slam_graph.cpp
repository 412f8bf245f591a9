// The SLAM layer's odometry path, loops and updates (slam_graph.hpp); sightings in slam_graph_sightings.cpp, lifelong
// thinning in slam_graph_thinning.cpp, state and forgetting in slam_graph_state.cpp.
#include "estimators/slam/slam_graph.hpp"

#include "assoc/chi_square.hpp"
#include "estimators/lie/planar_axes.hpp"
#include "estimators/lie/pose_covariance.hpp"
#include "estimators/slam/jump_covariance.hpp"
#include "estimators/slam/loop_gate.hpp"
#include "estimators/slam/pose_factors.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <set>

namespace sextant::slam {
namespace {

graph::IncrementalOptions smoother_options(const SlamOptions& o, bool planar) {
  graph::IncrementalOptions s = o.smoother;
  s.kernel = o.robust;
  s.kernel_width = kernel_width_for(o, planar);
  return s;
}

/// The configured kernel width, or the one "auto" gives a residual of `dimension` gated at `probability`.
double auto_kernel_width(const SlamOptions& options, int dimension, double probability) {
  if (options.kernel_width) return *options.kernel_width;
  const double q = assoc::chi2_quantile(dimension, probability);
  return options.robust == graph::RobustKernel::kDcs ? q : std::sqrt(q);
}

}  // namespace

double kernel_width_for(const SlamOptions& options, bool planar) {
  return auto_kernel_width(options, planar ? 3 : 6, options.loop_gate_probability);
}

double sighting_kernel_width_for(const SlamOptions& options, bool planar) {
  return auto_kernel_width(options, planar ? 2 : 3, options.landmarks.gate_probability);
}

SlamGraph::SlamGraph(const SlamOptions& options) : options_(options), proposer_(options.proposals) {
  KeyframeSelector check(options.keyframes);  // throws std::invalid_argument for bad thresholds
  (void)check;
  for (const bool planar : {false, true}) {
    const int kind = planar ? 1 : 0;
    loop_gate_[kind] = assoc::chi2_quantile(planar ? 3 : 6, options.loop_gate_probability);
    sighting_gate_[kind] = assoc::chi2_quantile(planar ? 2 : 3, options.landmarks.gate_probability);
    sighting_width_[kind] = sighting_kernel_width_for(options, planar);
  }
}

graph::IncrementalSmoother& SlamGraph::smoother_for(bool planar) {
  auto& s = smoothers_[planar ? 1 : 0];
  if (!s) s = std::make_unique<graph::IncrementalSmoother>(smoother_options(options_, planar));
  return *s;
}

SlamGraph::Body& SlamGraph::body_for(const std::string& name, bool planar) {
  auto it = bodies_.find(name);
  if (it != bodies_.end()) return it->second;
  KeyframeSelectorOptions ko = options_.keyframes;
  ko.planar = planar;
  Body body;
  body.frame = name;  // a map frame of its own until it joins another (slam_graph_fleet.cpp)
  body.planar = planar;
  body.selector = KeyframeSelector(ko);
  body.smoother = &smoother_for(planar);
  if (local_input_ && name == input_body_) body.clock = input_utime_;  // its first input, being handled
  return bodies_.emplace(name, std::move(body)).first->second;
}

SE3 SlamGraph::estimate(const Body& b, int variable) const {
  return b.smoother->graph().variables()[static_cast<size_t>(variable)].as_se3();
}

Eigen::Vector3d SlamGraph::position(const Body& b, int variable) const {
  return b.smoother->graph().variables()[static_cast<size_t>(variable)].position();
}

void SlamGraph::add_factor(Body& b, std::unique_ptr<graph::Factor> factor, FactorRole role, bool robust,
                           std::optional<double> width) {
  b.smoother->add_factor(std::move(factor), robust, width);
  factor_tags_[b.planar ? 1 : 0].push_back({role, robust, width});
}

void SlamGraph::add_odometry(const std::string& name, const OdometryInput& o, SlamListener& listener) {
  begin_local_input(name, o.utime);
  handle_odometry(name, o, listener);
  end_local_input(o.utime, listener);
}

void SlamGraph::add_loop(const std::string& name, const LoopInput& l, SlamListener& listener) {
  const int64_t utime = std::max(l.utime_from, l.utime_to);
  begin_local_input(name, utime);
  handle_loop(name, l, listener);
  end_local_input(utime, listener);
}

void SlamGraph::begin_local_input(const std::string& body, int64_t utime) {
  local_input_ = true;
  input_body_ = body;
  input_utime_ = utime;
  if (const auto it = bodies_.find(body); it != bodies_.end()) {
    Body& root = bodies_.at(it->second.frame);
    root.clock = std::max(root.clock, utime);
  }
}

void SlamGraph::end_local_input(int64_t utime, SlamListener& listener) {
  const auto it = bodies_.find(input_body_);
  if (it != bodies_.end() && !it->second.remote) {
    Body& root = bodies_.at(it->second.frame);
    root.clock = std::max(root.clock, utime);
    if (!deferred_.active && frame_owes(it->second.frame) && !waits_for_period(it->second))
      run_deferred(listener, false);
  }
  local_input_ = false;
}

bool SlamGraph::waits_for_period(const Body& b) const {
  if (!local_input_ || !(options_.solve_period_s > 0)) return false;
  const Body& root = bodies_.at(b.frame);
  if (root.reported == kNever) return false;
  // A spread reordering advances one slice per update: held back, its updates would span many periods and the one
  // that puts it in place would take all that waited meanwhile at once (a rebuild of hundreds of factors).
  if (b.smoother != nullptr && b.smoother->reordering()) return false;
  return root.clock < root.reported + static_cast<int64_t>(options_.solve_period_s * 1e6);
}

bool SlamGraph::frame_owes(const std::string& frame) const {
  if (deferred_.frames.contains(frame)) return true;
  for (const auto& [name, utime] : deferred_.updated)
    if (const auto it = bodies_.find(name); it != bodies_.end() && it->second.frame == frame) return true;
  return false;
}

void SlamGraph::solve_owed(SlamListener& listener) {
  if (owes() && !deferred_.active) run_deferred(listener, false);
}

void SlamGraph::flush(SlamListener& listener) {
  if (owes() && !deferred_.active) run_deferred(listener);
}

void SlamGraph::handle_odometry(const std::string& name, const OdometryInput& o, SlamListener& listener) {
  const auto it = bodies_.find(name);
  const bool known = it != bodies_.end();
  if (known && it->second.remote) {
    ++counters_.fleet_remote_inputs;  // a body has one owner: its graph is built from another's contributions
    return;
  }
  Body& b = known ? it->second : body_for(name, o.planar);
  if (known && o.utime <= b.track.last_utime()) {
    ++counters_.odometry_out_of_order;
    return;
  }
  const SE3& odom = o.pose;
  // Sightings that waited for this message (taken after the previous one): anchored on the newest keyframe, their
  // part of the increment interpolated on the group, Delta_a = Exp(a Log Delta) with covariance a Q.
  std::vector<std::pair<SightingsInput, TrackPoint>> due_sightings;
  if (!b.track.empty()) {
    const SE3 delta = b.track.last_odom().between(odom);
    const Matrix6d q =
        regularized_increment_covariance(o.covariance, o.increment_covariance, o.planar, delta,
                                         b.track.last_odom_covariance(), options_.min_increment_variance);
    const SE3 keyframe_to_last = b.track.newest().odom.between(b.track.last_odom());
    while (!b.early_sightings.empty() && b.early_sightings.front().utime <= o.utime) {
      const double a = static_cast<double>(b.early_sightings.front().utime - b.track.last_utime()) /
                       static_cast<double>(o.utime - b.track.last_utime());
      const SE3 part = SE3::exp(a * delta.log());
      TrackPoint anchor{b.track.keyframes().size() - 1, keyframe_to_last * part,
                        compose_covariance(b.track.since_keyframe(), part, a * q)};
      due_sightings.emplace_back(std::move(b.early_sightings.front()), anchor);
      b.early_sightings.erase(b.early_sightings.begin());
    }
    b.track.extend_since_keyframe(delta, q);
  }
  while (!b.early_sightings.empty() && b.early_sightings.front().utime <= o.utime) {  // a body without keyframes
    counters_.sightings_before_keyframe += static_cast<int64_t>(b.early_sightings.front().sightings.size());
    b.early_sightings.erase(b.early_sightings.begin());
  }
  b.track.advance(o.utime, odom, o.covariance, static_cast<size_t>(options_.odometry_history));

  for (const auto& [sightings, anchor] : due_sightings) add_anchored_sightings(name, b, sightings, anchor, listener);
  on_keyframe_candidate(name, b, o, listener);
  // Loops that arrived before the odometry of their times: try them now that the odometry has reached them.
  if (!b.early_loops.empty()) {
    std::vector<LoopInput> due, later;
    for (auto& l : b.early_loops) {
      (own_time(name, l) <= b.track.last_utime() ? due : later).push_back(std::move(l));
    }
    b.early_loops = std::move(later);
    counters_.loops_waiting -= static_cast<int64_t>(due.size());
    for (const auto& l : due) handle_loop(name, l, listener);
  }
  // Other bodies' sightings of this one that its odometry had not reached.
  if (!b.early_seen.empty()) complete_seen(b, listener);
  // Other bodies' loops to a time of this one that its odometry had not reached.
  if (!b.early_halves.empty()) {
    std::vector<std::pair<std::string, BodyLoopHalf>> waiting = std::move(b.early_halves);
    b.early_halves.clear();
    counters_.loops_waiting -= static_cast<int64_t>(waiting.size());
    for (const auto& [from, h] : waiting) complete_body_loop(from, h, listener);
  }
}

void SlamGraph::complete_seen(Body& b, SlamListener& listener) {
  std::vector<std::pair<std::string, BodySightingHalf>> due, later;
  for (auto& x : b.early_seen) (x.second.utime <= b.track.last_utime() ? due : later).push_back(std::move(x));
  b.early_seen = std::move(later);
  std::set<std::string> frames;
  const size_t pending_before = pending_.sightings.size();
  for (const auto& [observer, h] : due) {
    if (!bodies_.contains(observer)) continue;  // forgotten meanwhile
    if (complete_body_sighting(observer, h, listener)) frames.insert(b.frame);
  }
  for (const std::string& f : frames) update_frame(f, listener);
  if (options_.fleet.enabled && (!frames.empty() || pending_.sightings.size() != pending_before))
    try_joins(b.frame, listener);
}

void SlamGraph::on_keyframe_candidate(const std::string& name, Body& b, const OdometryInput& o,
                                      SlamListener& listener) {
  const KeyframeDecision d = b.selector.decide(o.pose);
  if (d == KeyframeDecision::kImplausible) ++counters_.keyframes_rejected;
  if (d != KeyframeDecision::kKeyframe && d != KeyframeDecision::kReanchored) return;
  KeyframeContribution k;
  k.id = b.track.next_id();
  k.utime = o.utime;
  k.planar = b.planar;
  k.first = b.track.empty();
  k.reanchored = d == KeyframeDecision::kReanchored && !k.first;
  k.odom = o.pose;
  k.odom_covariance = o.covariance;
  if (!k.first) {
    k.edge = b.track.newest().odom.between(o.pose);
    k.edge_covariance = b.track.since_keyframe();
    if (k.reanchored) k.edge_covariance += jump_covariance(k.edge, b.planar);
  }
  // A keyframe that cannot enter (a covariance that cannot be inverted, a value the smoother refuses) is dropped: the
  // selector goes back to the last keyframe in the graph and the next edge, which spans it, accumulates from there.
  if (!add_keyframe_to_graph(name, b, k, listener)) drop_keyframe(b);
}

void SlamGraph::propose_loops(const std::string& name, const Body& b, int64_t utime, SlamListener& listener) {
  // Candidates among the keyframes in the graph (positions in the track; with lifelong thinning the places kept of
  // the older map), named by their keyframe ids.
  const auto& keyframes = b.track.keyframes();
  const int64_t k = static_cast<int64_t>(keyframes.size()) - 1;
  for (const LoopProposal& p : proposer_.propose(k)) {
    const TrackKeyframe& a = keyframes[static_cast<size_t>(p.from)];
    const TrackKeyframe& c = keyframes[static_cast<size_t>(p.to)];
    listener.loop_proposed(name, utime, KeyframeEstimate{a.id, a.utime, estimate(b, a.variable)},
                           KeyframeEstimate{c.id, c.utime, estimate(b, c.variable)}, p.random);
  }
}

void SlamGraph::drop_keyframe(Body& b) {
  ++counters_.odometry_edges_rejected;
  b.selector.reset_reference(b.track.empty() ? std::nullopt : std::optional<SE3>(b.track.newest().odom));
}

int64_t SlamGraph::own_time(const std::string& name, const LoopInput& l) {
  return l.body_to.empty() || l.body_to == name ? std::max(l.utime_from, l.utime_to) : l.utime_from;
}

void SlamGraph::forget_handled_before_restart(const std::string& name, Body& b, int64_t utime) {
  std::erase_if(b.early_sightings, [&](const SightingsInput& s) { return s.utime <= utime; });
  const size_t loops = b.early_loops.size();
  std::erase_if(b.early_loops, [&](const LoopInput& l) { return own_time(name, l) <= utime; });
  counters_.loops_waiting -= static_cast<int64_t>(loops - b.early_loops.size());
}

void SlamGraph::wait_for_odometry(Body& b, const LoopInput& l) {
  // Retried when the odometry gets there, within a bound per body (a far-future loop would otherwise wait forever).
  if (b.early_loops.size() < static_cast<size_t>(std::max(options_.max_waiting_loops, 0))) {
    b.early_loops.push_back(l);
    ++counters_.loops_waiting;
  } else {
    ++counters_.loops_waiting_dropped;
  }
}

void SlamGraph::handle_loop(const std::string& name, const LoopInput& l, SlamListener& listener) {
  auto it = bodies_.find(name);
  if (it != bodies_.end() && it->second.remote) {
    ++counters_.fleet_remote_inputs;
    return;
  }
  if (it == bodies_.end()) {
    ++counters_.loops_unknown_source;
    return;
  }
  Body& b = it->second;
  if (!l.body_to.empty() && l.body_to != name) {
    add_body_loop(name, b, l, listener);
    return;
  }
  const auto tolerance = static_cast<int64_t>(options_.loop_time_tolerance_s * 1e6);
  const auto end_from = b.track.resolve(l.keyframe_from, l.utime_from, tolerance);
  const auto end_to = b.track.resolve(l.keyframe_to, l.utime_to, tolerance);
  if ((!end_from || !end_to) && std::max(l.utime_from, l.utime_to) > b.track.last_utime()) {
    wait_for_odometry(b, l);
    return;
  }
  if (!end_from || !end_to || end_from->keyframe == end_to->keyframe) {
    ++counters_.loops_unmatched;
    return;
  }
  const KeyframeLoop loop = loop_on_keyframes(b.planar, l.relative, l.information, *end_from, *end_to);
  if (loop.widened) ++counters_.loops_on_thinned;
  if (!landing_checkable(*end_from, *end_to)) return;  // read off the track alone: no solve needed to refuse it
  // The gate reads the estimate of both ends: a keyframe added since the last update (the newest, which a matcher's
  // answer is usually about) is solved first, as it would be without the solve period.
  const auto solved = [&](size_t k) { return b.smoother->in_system(b.track.keyframes()[k].variable); };
  if (!solved(end_from->keyframe) || !solved(end_to->keyframe)) solve_owed(listener);
  const LoopContribution c{b.track.keyframes()[end_from->keyframe].id, b.track.keyframes()[end_to->keyframe].id, loop.z,
                           loop.information, loop.widened};
  if (!add_loop_on_keyframes(b, c)) return;
  listener.contributed({name, c});
  update(name, b, b.track.newest().utime, listener);
}

graph::IncrementalStatus SlamGraph::solve(graph::IncrementalSmoother& smoother) {
  const auto t0 = std::chrono::steady_clock::now();
  const graph::IncrementalStatus st = smoother.update();
  counters_.last_update_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  ++counters_.updates;
  counters_.rebuilds += st.rebuilt ? 1 : 0;
  counters_.relinearized_factors += st.relinearized_factors;
  if (!st.ok) ++counters_.optimizer_failures;
  return st;
}

void SlamGraph::update(const std::string& name, Body& b, int64_t utime, SlamListener& listener) {
  deferred_.dirty[b.planar ? 1 : 0] = true;
  deferred_.updated[name] = utime;
  if (!deferred_.active && !waits_for_period(b)) run_deferred(listener, false);
}

void SlamGraph::rebuild() {
  for (auto& s : smoothers_)
    if (s) s->rebuild();
}

const KeyframeTrack* SlamGraph::track(const std::string& name) const {
  auto it = bodies_.find(name);
  return it == bodies_.end() ? nullptr : &it->second.track;
}

std::vector<std::string> SlamGraph::bodies() const {
  std::vector<std::string> out;
  for (const auto& [name, b] : bodies_) out.push_back(name);
  return out;
}

std::vector<KeyframeEstimate> SlamGraph::keyframes(const std::string& name) const {
  std::vector<KeyframeEstimate> out;
  auto it = bodies_.find(name);
  if (it == bodies_.end()) return out;
  out.reserve(it->second.track.keyframes().size());
  for (const TrackKeyframe& k : it->second.track.keyframes())
    out.push_back(KeyframeEstimate{k.id, k.utime, estimate(it->second, k.variable)});
  return out;
}

std::vector<SlamLandmark> SlamGraph::landmarks(const std::string& name) const {
  std::vector<SlamLandmark> out;
  auto it = bodies_.find(name);
  if (it == bodies_.end()) return out;
  for (const auto& [id, l] : root_of(it->second).landmarks)
    out.push_back(
        SlamLandmark{id, it->second.smoother->graph().variables()[static_cast<size_t>(l.variable)].point, l.sightings});
  return out;
}

SlamGraph::NewestKeyframe SlamGraph::newest_keyframe(const std::string& name) const {
  const Body& b = bodies_.at(name);
  NewestKeyframe out;
  out.keyframe = &b.track.newest();
  out.estimate = estimate(b, out.keyframe->variable);
  const Eigen::MatrixXd marginal = b.smoother->marginal_covariance(out.keyframe->variable);
  if (marginal.size() > 0) out.covariance = b.planar ? embed_planar(marginal) : Matrix6d(marginal);
  return out;
}

bool SlamGraph::planar(const std::string& name) const {
  auto it = bodies_.find(name);
  return it != bodies_.end() && it->second.planar;
}

double SlamGraph::chi2(const std::string& name) const { return bodies_.at(name).smoother->chi2(); }

int64_t SlamGraph::graph_keyframes() const {
  int64_t n = 0;
  for (const auto& [name, b] : bodies_) n += static_cast<int64_t>(b.track.keyframes().size());
  return n;
}

int64_t SlamGraph::graph_landmarks() const {
  int64_t n = 0;
  for (const auto& [name, b] : bodies_) n += static_cast<int64_t>(b.landmarks.size());
  return n;
}

int64_t SlamGraph::graph_factors() const {
  int64_t n = 0;
  for (const auto& s : smoothers_)
    if (s) n += static_cast<int64_t>(s->graph().factors().size());
  return n;
}

}  // namespace sextant::slam
