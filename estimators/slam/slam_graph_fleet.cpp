// The SLAM layer's fleet (slam_graph.hpp, "Fleet"): robot sightings and inter-robot loops, evidence between map
// frames, the joining of two frames, and the frames' names.
#include "estimators/lie/planar_axes.hpp"
#include "estimators/slam/loop_gate.hpp"
#include "estimators/slam/pose_factors.hpp"
#include "estimators/slam/sighting_model.hpp"
#include "estimators/slam/slam_graph.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <set>

namespace sextant::slam {

/// The placement evidence between two frames and where each item came from: -1 a landmark both maps hold, else an
/// index into pending_.sightings (from_sighting) or pending_.loops.
struct SlamGraph::Evidence {
  std::vector<PlacementEvidence> items;
  std::vector<std::pair<bool, int>> origin;  // (from a pending sighting, index); index -1: a landmark
};

std::string SlamGraph::frame_of(const std::string& name) const {
  auto it = bodies_.find(name);
  return it == bodies_.end() ? std::string() : it->second.frame;
}

std::map<std::string, std::vector<std::string>> SlamGraph::frames() const {
  std::map<std::string, std::vector<std::string>> out;
  for (const auto& [name, b] : bodies_) out[b.frame].push_back(name);
  return out;
}

void SlamGraph::propose_fleet_loops(const std::string& name, const Body& b, int64_t utime, SlamListener& listener) {
  if (!(options_.fleet.proposal_radius > 0)) return;
  const TrackKeyframe& k = b.track.newest();
  const SE3 here = estimate(b, k.variable);
  const Eigen::Vector3d at = here.translation();
  for (const auto& [other, o] : bodies_) {
    if (other == name || o.frame != b.frame) continue;
    const TrackKeyframe* nearest = nullptr;
    double best = options_.fleet.proposal_radius;
    for (const TrackKeyframe& c : o.track.keyframes()) {
      const double d = (position(o, c.variable) - at).norm();
      if (d <= best) best = d, nearest = &c;
    }
    if (nearest != nullptr)
      listener.fleet_loop_proposed(name, utime, KeyframeEstimate{k.id, k.utime, here}, other,
                                   KeyframeEstimate{nearest->id, nearest->utime, estimate(o, nearest->variable)});
  }
}

bool SlamGraph::add_sighting_factor(const SightingLink& s) {
  const auto a = bodies_.find(s.observer), o = bodies_.find(s.observed);
  if (a == bodies_.end() || o == bodies_.end()) return false;
  const auto ka = a->second.track.position_of(s.observer_keyframe);
  const auto ko = o->second.track.position_of(s.observed_keyframe);
  if (!ka || !ko) {
    ++counters_.fleet_sightings_unplaced;  // an anchor thinned away while the sighting waited
    return false;
  }
  Body& observer = a->second;
  const bool planar = observer.planar;
  const TrackKeyframe& kfa = observer.track.keyframes()[*ka];
  const TrackKeyframe& kfo = o->second.track.keyframes()[*ko];
  const SightingModel model(planar, estimate(observer, kfa.variable), {*ka, s.observer_motion, s.observer_covariance},
                            s.sensor_in_body);
  Eigen::VectorXd z;
  Eigen::MatrixXd R;
  if (!model.measurement(s.sighting, z, R)) {
    ++counters_.sightings_malformed;
    return false;
  }
  const SE3 seen = estimate(o->second, kfo.variable) * s.observed_motion;
  const SightingModel::Evaluation ev = model.evaluate(z, seen.translation());
  // The seen body's odometry from its keyframe to the sighting is uncertain too: its translation moves the seen
  // point by R_seen dt, so R gains J_p R_seen Sigma_t R_seen' J_p' (the rotation part does not move the origin).
  const int n = planar ? 2 : 3;
  const Eigen::MatrixXd j = ev.d_landmark * seen.rotation().matrix().topLeftCorner(n, n);
  const Eigen::MatrixXd r_seen = R + j * s.observed_covariance.topLeftCorner(n, n) * j.transpose();
  try {
    add_factor(observer,
               std::make_unique<graph::PoseObservationFactor>(kfa.variable, kfo.variable, model.model(), z,
                                                              model.information(ev, r_seen), model.sensor_in_keyframe(),
                                                              s.observed_motion.translation()),
               FactorRole::kLoop, true, sighting_width_[planar ? 1 : 0]);
  } catch (const std::invalid_argument&) {
    ++counters_.sightings_malformed;
    return false;
  }
  ++counters_.fleet_sightings;
  return true;
}

bool SlamGraph::add_loop_factor(const LoopLink& l) {
  const auto a = bodies_.find(l.from), b = bodies_.find(l.to);
  if (a == bodies_.end() || b == bodies_.end()) return false;
  const auto ka = a->second.track.position_of(l.from_keyframe);
  const auto kb = b->second.track.position_of(l.to_keyframe);
  if (!ka || !kb) {
    ++counters_.loops_unmatched;
    return false;
  }
  Body& from = a->second;
  const int va = from.track.keyframes()[*ka].variable, vb = b->second.track.keyframes()[*kb].variable;
  // The gate against the estimate: the relative pose's covariance from the two keyframes' marginals (their
  // correlation ignored), P = Ad(D^-1) P_a Ad(D^-1)' + P_b with D = X_a^-1 X_b.
  const SE3 predicted = estimate(from, va).between(estimate(b->second, vb));
  const auto marginal = [&](int v) {
    const Eigen::MatrixXd m = gate_marginal(from, v);
    return m.size() == 0 ? Matrix6d::Zero().eval() : from.planar ? embed_planar(m) : Matrix6d(m);
  };
  const Matrix6d ad = predicted.inverse().adjoint();
  const Matrix6d path = ad * marginal(va) * ad.transpose() + marginal(vb);
  const KeyframeLoop loop{l.z, l.information, false};
  if (!(loop_mahalanobis(from.planar, loop, predicted, path, 1.0) <= loop_gate_[from.planar ? 1 : 0])) {
    ++counters_.loops_rejected;
    return false;
  }
  try {
    add_factor(from, loop_factor(from.planar, va, vb, l.z, l.information), FactorRole::kLoop, true, std::nullopt);
  } catch (const std::invalid_argument&) {
    ++counters_.loops_rejected;
    return false;
  }
  ++counters_.fleet_loops;
  ++counters_.loops_accepted;
  return true;
}

void SlamGraph::add_body_loop(const std::string& name, Body& b, const LoopInput& l, SlamListener& listener) {
  auto it = bodies_.find(l.body_to);
  if (!options_.fleet.enabled || (it != bodies_.end() && it->second.planar != b.planar)) {
    ++counters_.loops_unknown_source;
    return;
  }
  const auto tolerance = static_cast<int64_t>(options_.loop_time_tolerance_s * 1e6);
  const auto end_from = b.track.resolve(l.keyframe_from, l.utime_from, tolerance);
  if (!end_from) {
    if (l.utime_from > b.track.last_utime())
      wait_for_odometry(b, l);
    else
      ++counters_.loops_unmatched;
    return;
  }
  // This end is the owner's to anchor; the other body's owner anchors the other end (graph_contribution.hpp).
  const BodyLoopHalf half{l, anchor_of(b, *end_from)};
  listener.contributed({name, half});
  if (it == bodies_.end()) {
    ++counters_.loops_unknown_source;
    return;
  }
  complete_body_loop(name, half, listener);
}

SlamGraph::Evidence SlamGraph::evidence_between(const std::string& a, const std::string& b) {
  Evidence ev;
  const Body& ra = bodies_.at(a);
  const Body& rb = bodies_.at(b);
  const auto point = [&](const Landmark& l, const Body& r) {
    return r.smoother->graph().variables()[static_cast<size_t>(l.variable)].point;
  };
  // A landmark is evidence once both maps know where it is to within half the inlier distance (its marginal's
  // largest standard deviation): a landmark placed by a sighting or two is off by more than the agreement tested.
  const double max_variance = std::pow(options_.fleet.placement.inlier_distance / 2, 2);
  const auto known = [&](const Body& r, const Landmark& l) {
    const Eigen::MatrixXd m = gate_marginal(r, l.variable);
    return m.size() > 0 && Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(m).eigenvalues().maxCoeff() <= max_variance;
  };
  for (const auto& [id, la] : ra.landmarks) {
    const auto lb = rb.landmarks.find(id);
    if (lb == rb.landmarks.end() || !known(ra, la) || !known(rb, lb->second)) continue;
    ev.items.push_back({PlacementEvidence::Kind::kLandmark, point(la, ra), point(lb->second, rb), SE3()});
    ev.origin.emplace_back(false, -1);
  }
  for (size_t k = 0; k < pending_.sightings.size(); ++k) {
    const SightingLink& s = pending_.sightings[k];
    const Body& observer = bodies_.at(s.observer);
    const Body& observed = bodies_.at(s.observed);
    const bool forward = observer.frame == a && observed.frame == b;
    if (!forward && !(observer.frame == b && observed.frame == a)) continue;
    const auto ka = observer.track.position_of(s.observer_keyframe);
    const auto ko = observed.track.position_of(s.observed_keyframe);
    if (!ka || !ko) continue;
    const SightingModel model(observer.planar, estimate(observer, observer.track.keyframes()[*ka].variable),
                              {*ka, s.observer_motion, s.observer_covariance}, s.sensor_in_body);
    const Eigen::Vector3d seen = model.landmark_from(s.sighting);  // in the observer's frame
    // The seen point's uncertainty: range variance plus the angles' times the range squared (3 sigma).
    const Eigen::Matrix3d& c = s.sighting.covariance;
    const double angles = c(1, 1) + (observer.planar ? 0.0 : c(2, 2));
    const double tolerance = 3 * std::sqrt(std::max(0.0, c(0, 0) + s.sighting.range * s.sighting.range * angles));
    const Eigen::Vector3d own =
        (estimate(observed, observed.track.keyframes()[*ko].variable) * s.observed_motion).translation();
    ev.items.push_back(
        {PlacementEvidence::Kind::kBodySighting, forward ? seen : own, forward ? own : seen, SE3(), tolerance});
    ev.origin.emplace_back(true, static_cast<int>(k));
  }
  for (size_t k = 0; k < pending_.loops.size(); ++k) {
    const LoopLink& l = pending_.loops[k];
    const Body& from = bodies_.at(l.from);
    const Body& to = bodies_.at(l.to);
    const bool forward = from.frame == a && to.frame == b;
    if (!forward && !(from.frame == b && to.frame == a)) continue;
    const auto kf = from.track.position_of(l.from_keyframe);
    const auto kt = to.track.position_of(l.to_keyframe);
    if (!kf || !kt) continue;
    // T_from_to = X_from z X_to^-1 (each X in its own frame).
    const SE3 x_from = estimate(from, from.track.keyframes()[*kf].variable);
    const SE3 x_to = estimate(to, to.track.keyframes()[*kt].variable);
    const SE3 t = x_from * l.z * x_to.inverse();
    const Eigen::Vector3d &p_from = x_from.translation(), &p_to = x_to.translation();
    ev.items.push_back(
        {PlacementEvidence::Kind::kLoop, forward ? p_from : p_to, forward ? p_to : p_from, forward ? t : t.inverse()});
    ev.origin.emplace_back(false, static_cast<int>(k));
  }
  return ev;
}

std::vector<std::string> SlamGraph::linked_frames(const std::string& frame) const {
  std::set<std::string> out;
  const auto link = [&](const std::string& x, const std::string& y) {
    if (x == frame && y != frame) out.insert(y);
    if (y == frame && x != frame) out.insert(x);
  };
  for (const SightingLink& s : pending_.sightings) link(bodies_.at(s.observer).frame, bodies_.at(s.observed).frame);
  for (const LoopLink& l : pending_.loops) link(bodies_.at(l.from).frame, bodies_.at(l.to).frame);
  const Body& root = bodies_.at(frame);
  for (const auto& [name, b] : bodies_) {
    if (b.frame != name || name == frame || b.planar != root.planar || out.contains(name)) continue;
    for (const auto& [id, l] : b.landmarks)
      if (root.landmarks.contains(id)) {
        out.insert(name);
        break;
      }
  }
  return {out.begin(), out.end()};
}

void SlamGraph::try_joins(const std::string& frame, SlamListener& listener) {
  if (!options_.fleet.enabled) return;
  if (deferred_.active) {
    deferred_.joins.insert(frame);
    return;
  }
  std::string current = frame;
  for (const std::string& other : linked_frames(frame)) {
    if (!bodies_.contains(other) || bodies_.at(other).frame != other) continue;  // joined meanwhile
    auto& last = join_attempts_[std::minmax(current, other)];
    if (last != 0 && counters_.keyframes - last < options_.fleet.join_every_keyframes) continue;
    last = std::max<int64_t>(counters_.keyframes, 1);
    if (owes()) run_deferred(listener);  // the placement reads the estimates: what is owed is solved first
    if (try_join(current, other, listener)) current = std::min(current, other);
  }
}

bool SlamGraph::try_join(const std::string& a, const std::string& b, SlamListener& listener) {
  if (!options_.fleet.enabled || a == b) return false;
  const std::string keep = std::min(a, b), gone = std::max(a, b);
  if (bodies_.at(gone).remote) return false;  // its owner decides (FrameJoin)
  const Evidence ev = evidence_between(a, b);
  if (ev.items.size() < static_cast<size_t>(options_.fleet.placement.min_support)) return false;
  const Placement p = place_frames(ev.items, bodies_.at(a).planar, options_.fleet.placement);
  if (!p.placed) return false;
  std::vector<char> inlier(ev.items.size(), 0);
  for (size_t i : p.inliers) inlier[i] = 1;
  const SE3 keep_from_gone = keep == a ? p.a_from_b : p.a_from_b.inverse();
  listener.contributed({gone, FrameJoin{keep, keep_from_gone}});
  join_frames(keep, gone, keep_from_gone, ev, inlier, listener);
  return true;
}

bool SlamGraph::apply_join(const std::string& gone, const FrameJoin& j, SlamListener& listener) {
  const auto named = bodies_.find(j.keep);
  if (bodies_.at(gone).frame != gone || named == bodies_.end() || named->second.planar != bodies_.at(gone).planar) {
    ++counters_.fleet_joins_refused;
    return false;
  }
  const auto [keep, keep_from_named] = current_frame(j.keep);
  if (keep != named->second.frame || !(keep < gone)) {  // frames move only into earlier names
    ++counters_.fleet_joins_refused;
    return false;
  }
  const SE3 keep_from_gone = keep_from_named * j.keep_from_gone;
  // The evidence this graph holds between the two frames is classified by the owner's placement, as the owner's
  // own evidence was by it (this graph may hold items the owner did not have yet, and the reverse).
  const Evidence ev = evidence_between(keep, gone);
  std::vector<char> inlier(ev.items.size(), 0);
  for (size_t i = 0; i < ev.items.size(); ++i)
    inlier[i] = agrees(ev.items[i], keep_from_gone, bodies_.at(gone).planar, options_.fleet.placement) ? 1 : 0;
  join_frames(keep, gone, keep_from_gone, ev, inlier, listener);
  ++counters_.fleet_joins_remote;
  return true;
}

std::pair<std::string, SE3> SlamGraph::current_frame(const std::string& frame) const {
  std::pair<std::string, SE3> at{frame, SE3()};
  // Joins lead to earlier names, so the chain ends; a forgotten root's successor (hand_over_frame) may break that
  // order, hence the bound.
  for (size_t step = 0; step <= moved_frames_.size(); ++step) {
    const auto it = moved_frames_.find(at.first);
    if (it == moved_frames_.end()) break;
    at = {it->second.first, it->second.second * at.second};
  }
  return at;
}

void SlamGraph::join_frames(const std::string& keep, const std::string& gone, const SE3& keep_from_gone,
                            const Evidence& ev, const std::vector<char>& inlier, SlamListener& listener) {
  // The links between the two frames leave the pending lists: those that agree with the placement become factors
  // once the frames are one, the others are outliers.
  std::vector<SightingLink> sightings;
  std::vector<LoopLink> loops;
  std::set<int> taken_sightings, taken_loops;
  for (size_t i = 0; i < ev.items.size(); ++i) {
    const auto [is_sighting, k] = ev.origin[i];
    if (k < 0) continue;
    (is_sighting ? taken_sightings : taken_loops).insert(k);
    if (!inlier[i]) {
      ++counters_.fleet_outliers;
      continue;
    }
    if (is_sighting)
      sightings.push_back(pending_.sightings[static_cast<size_t>(k)]);
    else
      loops.push_back(pending_.loops[static_cast<size_t>(k)]);
  }
  const auto erase_taken = [](auto& list, const std::set<int>& taken) {
    for (auto it = taken.rbegin(); it != taken.rend(); ++it) list.erase(list.begin() + *it);
  };
  erase_taken(pending_.sightings, taken_sightings);
  erase_taken(pending_.loops, taken_loops);
  counters_.fleet_pending -= static_cast<int64_t>(taken_sightings.size() + taken_loops.size());
  merge_frame_variables(keep, gone, keep_from_gone);
  moved_frames_[gone] = {keep, keep_from_gone};
  ++counters_.fleet_joins;
  for (const SightingLink& s : sightings) add_sighting_factor(s);
  for (const LoopLink& l : loops) add_loop_factor(l);
  update_frame(keep, listener);
}

void SlamGraph::update_frame(const std::string& frame, SlamListener& listener) {
  const Body& root = bodies_.at(frame);
  deferred_.dirty[root.planar ? 1 : 0] = true;
  deferred_.frames.insert(frame);
  if (!deferred_.active && !waits_for_period(root)) run_deferred(listener, false);
}

void SlamGraph::merge_frame_variables(const std::string& keep, const std::string& gone, const SE3& keep_from_gone) {
  Body& rk = bodies_.at(keep);
  Body& rg = bodies_.at(gone);
  const int kind = rk.planar ? 1 : 0;
  std::vector<graph::Variable> vars = rk.smoother->graph().variables();
  const auto move = [&](graph::Variable& v) {
    if (v.kind == graph::VariableKind::kPose2)
      v.pose2 = SE2::from_se3(keep_from_gone * v.pose2.to_se3());
    else if (v.kind == graph::VariableKind::kPose3)
      v.pose3 = keep_from_gone * v.pose3;
    else
      v.point = keep_from_gone * v.point;
    if (v.kind == graph::VariableKind::kPoint2) v.point.z() = 0;
  };
  for (auto& [name, b] : bodies_) {
    if (b.frame != gone) continue;
    for (const TrackKeyframe& k : b.track.keyframes()) {
      graph::Variable& v = vars[static_cast<size_t>(k.variable)];
      move(v);
      v.fixed = false;  // the gone frame's gauge: its root's first keyframe
    }
    b.frame = keep;
  }
  std::vector<int> merge_into(vars.size(), -1);
  for (auto& [id, l] : rg.landmarks) {
    move(vars[static_cast<size_t>(l.variable)]);
    auto k = rk.landmarks.find(id);
    if (k == rk.landmarks.end()) {
      rk.landmarks.emplace(id, l);
    } else {
      merge_into[static_cast<size_t>(l.variable)] = k->second.variable;
      k->second.sightings += l.sightings;
    }
  }
  rg.landmarks.clear();
  commit_rebuilt(kind, rebuilt(kind, vars, merge_into));
}

}  // namespace sextant::slam
