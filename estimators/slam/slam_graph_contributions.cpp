// The SLAM layer's back end (slam_graph.hpp, graph_contribution.hpp): what one contribution adds to the graph, for a
// local body's (made by the front end just before) and a remote one's (apply), and the wait of a whole robot sighting
// or inter-robot loop for a keyframe of the other body.
#include "estimators/slam/loop_gate.hpp"
#include "estimators/slam/pose_factors.hpp"
#include "estimators/slam/slam_graph.hpp"

#include <algorithm>
#include <optional>

namespace sextant::slam {
namespace {

/// Appends to a bounded list of placement evidence, the oldest item going when it is full (counted).
template <class T>
void push_bounded(std::vector<T>& list, T item, int max_pending, SlamCounters& counters) {
  if (list.size() >= static_cast<size_t>(std::max(max_pending, 1))) {
    list.erase(list.begin());
    ++counters.fleet_pending_dropped;
    --counters.fleet_pending;
  }
  list.push_back(std::move(item));
  ++counters.fleet_pending;
}

/// The time of the body's own odometry a contribution of the body was made at (its keyframe, its sightings, its end
/// of a robot sighting or of an inter-robot loop); none for the others.
std::optional<int64_t> odometry_time(const GraphContribution::What& what) {
  if (const auto* k = std::get_if<KeyframeContribution>(&what)) return k->utime;
  if (const auto* s = std::get_if<SightingsContribution>(&what)) return s->sightings.utime;
  if (const auto* h = std::get_if<BodySightingHalf>(&what)) return h->utime;
  if (const auto* l = std::get_if<BodyLoopHalf>(&what)) return l->loop.utime_from;
  return std::nullopt;
}

}  // namespace

bool SlamGraph::remote(const std::string& name) const {
  auto it = bodies_.find(name);
  return it != bodies_.end() && it->second.remote;
}

std::optional<TrackPoint> SlamGraph::point_of(const Body& b, const KeyframeAnchor& a) const {
  const auto at = b.track.position_of(a.keyframe);
  if (!at) return std::nullopt;
  return TrackPoint{*at, a.motion, a.covariance};
}

KeyframeAnchor SlamGraph::anchor_of(const Body& b, const TrackPoint& p) const {
  return KeyframeAnchor{b.track.keyframes()[p.keyframe].id, p.motion, p.covariance};
}

bool SlamGraph::add_keyframe_to_graph(const std::string& name, Body& b, const KeyframeContribution& k,
                                      SlamListener& listener) {
  // A remote body's stream that starts after its first keyframe (its owner no longer had the beginning) starts a
  // frame of its own at the first keyframe that arrives, as a new body does.
  const bool starts = b.track.empty();
  if (!starts && b.remote && b.track.newest().id != k.id - 1) return false;  // not the keyframe after the newest
  TrackKeyframe node;
  node.id = k.id;
  node.utime = k.utime;
  node.odom = k.odom;
  node.odom_covariance = k.odom_covariance;
  std::unique_ptr<graph::Factor> edge_factor;
  if (!starts) {
    node.edge = k.edge;
    node.edge_covariance = k.edge_covariance;
    edge_factor = odometry_factor(b.planar, b.track.newest().variable, -1, node.edge, node.edge_covariance);
    if (!edge_factor) return false;
  }
  graph::Variable v;
  v.id = next_variable_id_++;
  v.kind = b.planar ? graph::VariableKind::kPose2 : graph::VariableKind::kPose3;
  v.fixed = starts;  // the body's map frame: its odometry frame at the first keyframe
  const SE3 initial = starts ? k.odom : estimate(b, b.track.newest().variable) * node.edge;
  if (b.planar)
    v.pose2 = SE2::from_se3(initial);
  else
    v.pose3 = initial;
  try {
    node.variable = b.smoother->add_variable(v);
    if (edge_factor)
      add_factor(b, edge_factor->rebind({b.track.newest().variable, node.variable}), FactorRole::kOdometry, false,
                 std::nullopt);
  } catch (const std::invalid_argument&) {
    return false;  // a non-finite pose or information: never reaches the smoother's system
  }
  if (b.remote) b.track.advance(k.utime, k.odom, k.odom_covariance, static_cast<size_t>(options_.odometry_history));
  b.track.add_keyframe(std::move(node));
  ++counters_.keyframes;
  if (k.reanchored) ++counters_.keyframes_reanchored;
  if (!b.remote) listener.contributed({name, k});
  update(name, b, k.utime, listener);
  if (!b.remote && options_.propose_loops) propose_loops(name, b, k.utime, listener);
  if (!b.remote && options_.propose_loops && options_.fleet.enabled) propose_fleet_loops(name, b, k.utime, listener);
  maybe_thin(b.planar, listener);
  retry_waiting(listener);
  return true;
}

bool SlamGraph::landing_checkable(const TrackPoint& from, const TrackPoint& to) {
  if (landing_sigma(from, to) <= options_.loop_max_landing_sigma) return true;
  ++counters_.loops_rejected;
  return false;
}

bool SlamGraph::add_loop_on_keyframes(Body& b, const LoopContribution& l) {
  const auto from = b.track.position_of(l.from_keyframe), to = b.track.position_of(l.to_keyframe);
  if (!from || !to || *from == *to) {
    ++counters_.loops_unmatched;
    return false;
  }
  const int vf = b.track.keyframes()[*from].variable, vt = b.track.keyframes()[*to].variable;
  if (!b.remote) {  // a remote body's loops passed its owner's gate
    const Matrix6d path = b.track.odometry_path(*from, *to).second;
    const SE3 predicted = estimate(b, vf).between(estimate(b, vt));
    const KeyframeLoop loop{l.z, l.information, l.widened};
    if (!(loop_mahalanobis(b.planar, loop, predicted, path, options_.loop_gate_odometry_scale) <=
          loop_gate_[b.planar ? 1 : 0])) {
      ++counters_.loops_rejected;
      return false;
    }
  }
  try {
    add_factor(b, loop_factor(b.planar, vf, vt, l.z, l.information), FactorRole::kLoop, true, std::nullopt);
  } catch (const std::invalid_argument&) {
    ++counters_.loops_rejected;  // an information the caller let through but the smoother cannot use
    return false;
  }
  ++counters_.loops_accepted;
  return true;
}

bool SlamGraph::complete_body_sighting(const std::string& observer, const BodySightingHalf& h, SlamListener& listener) {
  auto it = bodies_.find(h.observed);
  if (it != bodies_.end() && it->second.remote) return false;  // its owner anchors the observed end
  if (it != bodies_.end() && !it->second.track.empty() && h.utime > it->second.track.last_utime()) {
    // Ahead of the seen body's odometry (its stream is behind the observer's, or another daemon's half came early):
    // anchored exactly once the odometry passes the time (add_odometry), within a bound.
    Body& o = it->second;
    if (o.early_seen.size() >= static_cast<size_t>(std::max(options_.fleet.max_pending, 1))) {
      o.early_seen.erase(o.early_seen.begin());
      ++counters_.fleet_sightings_unplaced;
    }
    o.early_seen.emplace_back(observer, h);
    return false;
  }
  const std::optional<TrackPoint> at = it == bodies_.end() || it->second.planar != bodies_.at(observer).planar
                                           ? std::nullopt
                                           : it->second.track.anchor_at(h.utime);
  if (!at) {
    ++counters_.fleet_sightings_unplaced;
    return false;
  }
  const GraphContribution whole{h.observed, BodySighting{observer, h.utime, h.sensor_in_body, h.sighting, h.observer,
                                                         anchor_of(it->second, *at)}};
  if (completed_before_restart(whole)) return false;
  listener.contributed(whole);
  return add_whole(whole);
}

bool SlamGraph::complete_body_loop(const std::string& from, const BodyLoopHalf& h, SlamListener& listener) {
  auto it = bodies_.find(h.loop.body_to);
  if (it == bodies_.end() || it->second.remote) return false;  // unknown here, or its owner anchors the "to" end
  Body& o = it->second;
  const auto tolerance = static_cast<int64_t>(options_.loop_time_tolerance_s * 1e6);
  const auto end_to = o.track.resolve(h.loop.keyframe_to, h.loop.utime_to, tolerance);
  if (!end_to) {
    if (h.loop.utime_to <= o.track.last_utime()) {
      ++counters_.loops_unmatched;
    } else if (o.early_halves.size() < static_cast<size_t>(std::max(options_.max_waiting_loops, 0))) {
      o.early_halves.emplace_back(from, h);  // completed with this body's next odometry
      ++counters_.loops_waiting;
    } else {
      ++counters_.loops_waiting_dropped;
    }
    return false;
  }
  const TrackPoint end_from{0, h.from.motion, h.from.covariance};
  if (!landing_checkable(end_from, *end_to)) return false;
  const KeyframeLoop kl = loop_on_keyframes(o.planar, h.loop.relative, h.loop.information, end_from, *end_to);
  const GraphContribution whole{
      h.loop.body_to, BodyLoop{from, h.from.keyframe, o.track.keyframes()[end_to->keyframe].id, kl.z, kl.information}};
  if (completed_before_restart(whole)) return false;
  listener.contributed(whole);
  const size_t pending_before = pending_.loops.size();
  const bool added = add_whole(whole);
  if (added) update_frame(o.frame, listener);
  if (pending_.loops.size() != pending_before) try_join(bodies_.at(from).frame, o.frame, listener);
  return added;
}

bool SlamGraph::keyframes_present(const GraphContribution& c) const {
  // A keyframe id at or past a body's next id has not arrived (an older one that is not in the graph was thinned:
  // waiting would not bring it back).
  const auto arrived = [&](const std::string& body, int64_t id) {
    auto it = bodies_.find(body);
    return it != bodies_.end() && !it->second.track.empty() && id < it->second.track.next_id();
  };
  if (const auto* s = std::get_if<BodySighting>(&c.what))
    return arrived(s->observer, s->observer_anchor.keyframe) && arrived(c.body, s->observed_anchor.keyframe);
  if (const auto* l = std::get_if<BodyLoop>(&c.what))
    return arrived(l->from, l->from_keyframe) && arrived(c.body, l->to_keyframe);
  if (const auto* j = std::get_if<FrameJoin>(&c.what)) return arrived(j->keep, 0);
  return true;
}

void SlamGraph::wait_for_keyframes(const GraphContribution& c) {
  if (waiting_wholes_.size() >= static_cast<size_t>(std::max(options_.fleet.max_pending, 1))) {
    waiting_wholes_.erase(waiting_wholes_.begin());
    ++counters_.fleet_contributions_dropped;
    --counters_.fleet_contributions_waiting;
  }
  waiting_wholes_.push_back(c);
  ++counters_.fleet_contributions_waiting;
}

void SlamGraph::retry_waiting(SlamListener& listener) {
  if (waiting_wholes_.empty()) return;
  std::vector<GraphContribution> due;
  for (auto it = waiting_wholes_.begin(); it != waiting_wholes_.end();) {
    if (keyframes_present(*it)) {
      due.push_back(std::move(*it));
      it = waiting_wholes_.erase(it);
      --counters_.fleet_contributions_waiting;
    } else {
      ++it;
    }
  }
  for (const GraphContribution& c : due) apply_contribution(c, listener);
}

bool SlamGraph::add_whole(const GraphContribution& c) {
  if (!keyframes_present(c)) {
    wait_for_keyframes(c);
    return false;
  }
  const std::string& frame = bodies_.at(c.body).frame;
  if (const auto* s = std::get_if<BodySighting>(&c.what)) {
    SightingLink link{s->observer,
                      c.body,
                      s->utime,
                      s->sensor_in_body,
                      s->sighting,
                      s->observer_anchor.keyframe,
                      s->observed_anchor.keyframe,
                      s->observer_anchor.motion,
                      s->observed_anchor.motion,
                      s->observer_anchor.covariance,
                      s->observed_anchor.covariance};
    if (bodies_.at(s->observer).frame == frame) return add_sighting_factor(link);
    push_bounded(pending_.sightings, std::move(link), options_.fleet.max_pending, counters_);
    return false;
  }
  const auto& l = std::get<BodyLoop>(c.what);
  LoopLink link{l.from, c.body, l.from_keyframe, l.to_keyframe, l.z, l.information};
  if (bodies_.at(l.from).frame == frame) return add_loop_factor(link);
  push_bounded(pending_.loops, std::move(link), options_.fleet.max_pending, counters_);
  return false;
}

bool SlamGraph::apply(const GraphContribution& c, SlamListener& listener) {
  auto it = bodies_.find(c.body);
  const auto* k = std::get_if<KeyframeContribution>(&c.what);
  // A body has one owner: a contribution about a local body is refused; a remote body starts with a keyframe.
  const bool acceptable =
      it != bodies_.end() ? it->second.remote && (k == nullptr || k->planar == it->second.planar) : k != nullptr;
  if (acceptable && it == bodies_.end()) body_for(c.body, k->planar).remote = true;
  const bool applied = acceptable && apply_contribution(c, listener);
  ++(applied ? counters_.fleet_contributions_applied : counters_.fleet_contributions_refused);
  return applied;
}

bool SlamGraph::adopt(const GraphContribution& c, SlamListener& listener) {
  auto it = bodies_.find(c.body);
  const auto* k = std::get_if<KeyframeContribution>(&c.what);
  const bool acceptable =
      it != bodies_.end() ? !it->second.remote && (k == nullptr || k->planar == it->second.planar) : k != nullptr;
  if (!acceptable) {
    ++counters_.fleet_contributions_refused;
    return false;
  }
  Body& b = it != bodies_.end() ? it->second : body_for(c.body, k->planar);
  if (const std::optional<int64_t> reached = odometry_time(c.what)) forget_handled_before_restart(c.body, b, *reached);
  if (std::holds_alternative<BodySightingHalf>(c.what) || std::holds_alternative<BodyLoopHalf>(c.what)) return true;
  if (std::holds_alternative<BodySighting>(c.what) || std::holds_alternative<BodyLoop>(c.what))
    adopted_wholes_.insert(whole_key(c));
  // The back end's remote path is the one that takes a contribution as it is: the body is remote while it runs.
  struct Local {
    Body& b;
    ~Local() { b.remote = false; }
  } local{b};
  b.remote = true;
  const bool applied = apply_contribution(c, listener);
  if (applied && k) b.selector.reset_reference(b.track.newest().odom);
  ++(applied ? counters_.fleet_contributions_applied : counters_.fleet_contributions_refused);
  return applied;
}

SlamGraph::WholeKey SlamGraph::whole_key(const GraphContribution& c) {
  // What the other body's half determines: a sighting's observer, time and marker id; a loop's two keyframes.
  if (const auto* s = std::get_if<BodySighting>(&c.what)) return {0, c.body, s->observer, s->utime, s->sighting.id};
  const auto& l = std::get<BodyLoop>(c.what);
  return {1, c.body, l.from, l.from_keyframe, l.to_keyframe};
}

int SlamGraph::apply_all(const std::vector<GraphContribution>& contributions, SlamListener& listener) {
  int applied = 0;
  deferred_.active = contributions.size() > 1;
  // Whatever happens (a contribution that throws is the stage's to recover from), the batch ends: updates owed stay
  // owed (the smoother's pending work, done by the next update or flush), placements asked for are not tried.
  struct EndOfBatch {
    Deferred& d;
    ~EndOfBatch() {
      d.active = false;
      d.joins.clear();
    }
  } end_of_batch{deferred_};
  for (const GraphContribution& c : contributions) {
    // Their gates and the placement's classification read the estimate: solved first.
    const bool reads_estimate = std::holds_alternative<LoopContribution>(c.what) ||
                                std::holds_alternative<BodyLoopHalf>(c.what) ||
                                std::holds_alternative<BodyLoop>(c.what) || std::holds_alternative<FrameJoin>(c.what);
    if (deferred_.active && reads_estimate) run_deferred(listener);
    applied += apply(c, listener) ? 1 : 0;
  }
  if (deferred_.active) run_deferred(listener);
  return applied;
}

void SlamGraph::run_deferred(SlamListener& listener, bool all) {
  const Deferred owed = std::move(deferred_);
  deferred_ = Deferred{};  // inactive while the owed work runs: a join it makes updates at once
  // Which frames report now: decided before any report moves a frame's clock.  Without a period (or outside a
  // local input) none waits.
  const bool every_frame = all || !local_input_ || !(options_.solve_period_s > 0);
  std::set<std::string> due;
  for (const auto& [name, b] : bodies_)
    if (!every_frame && b.frame == name && !waits_for_period(b)) due.insert(name);
  graph::IncrementalStatus st[2];
  for (int kind = 0; kind < 2; ++kind)
    if (owed.dirty[kind] && smoothers_[kind]) st[kind] = solve(*smoothers_[kind]);
  const auto report = [&](const std::string& name, const Body& b, int64_t utime, bool as_frame) {
    const int kind = b.planar ? 1 : 0;
    if (!owed.dirty[kind] || !st[kind].ok) return;
    if (!every_frame && !due.contains(b.frame)) {  // stays owed, and so does an update of its smoother to report with
      deferred_.dirty[kind] = true;
      as_frame ? void(deferred_.frames.insert(b.frame)) : void(deferred_.updated[name] = utime);
      return;
    }
    listener.updated(name, utime, st[kind]);
    Body& root = bodies_.at(b.frame);
    root.reported = root.clock;
  };
  for (const auto& [name, utime] : owed.updated)
    if (const auto it = bodies_.find(name); it != bodies_.end()) report(name, it->second, utime, false);
  for (const auto& [name, b] : bodies_)
    if (owed.frames.contains(b.frame) && !owed.updated.contains(name) && !b.track.empty())
      report(name, b, b.track.newest().utime, true);
  for (const std::string& frame : owed.joins)
    if (bodies_.contains(frame) && bodies_.at(frame).frame == frame) try_joins(frame, listener);
  deferred_.active = owed.active;
}

bool SlamGraph::apply_contribution(const GraphContribution& c, SlamListener& listener) {
  Body& b = bodies_.at(c.body);
  const size_t sightings_before = pending_.sightings.size(), loops_before = pending_.loops.size();
  bool added = false;
  if (const auto* k = std::get_if<KeyframeContribution>(&c.what)) return add_keyframe_to_graph(c.body, b, *k, listener);
  if (const auto* t = std::get_if<KeyframesThinned>(&c.what)) {
    // Taken out at this graph's next thinning; ids the body never had here, or has not yet, are ignored.
    for (int64_t id : t->keyframes)
      if (b.track.position_of(id)) b.owner_thinned.insert(id);
    return true;
  }
  if (const auto* j = std::get_if<FrameJoin>(&c.what)) {
    if (keyframes_present(c)) return apply_join(c.body, *j, listener);
    wait_for_keyframes(c);  // the kept frame's root has not arrived here yet
    return true;
  }
  if (const auto* s = std::get_if<SightingsContribution>(&c.what)) {
    const auto anchor = point_of(b, s->anchor);
    if (!anchor) return false;
    added = add_landmark_sightings(b, s->sightings, *anchor, nullptr, listener);
  } else if (const auto* l = std::get_if<LoopContribution>(&c.what)) {
    if (!add_loop_on_keyframes(b, *l)) return false;
    added = true;
  } else if (const auto* h = std::get_if<BodySightingHalf>(&c.what)) {
    added = complete_body_sighting(c.body, *h, listener);
  } else if (const auto* hl = std::get_if<BodyLoopHalf>(&c.what)) {
    complete_body_loop(c.body, *hl, listener);  // updates and joins itself
    return true;
  } else {
    added = add_whole(c);
  }
  if (added) update_frame(b.frame, listener);
  const bool new_evidence = pending_.sightings.size() != sightings_before || pending_.loops.size() != loops_before;
  if (options_.fleet.enabled && (added || new_evidence)) try_joins(b.frame, listener);
  return true;
}

}  // namespace sextant::slam
