// The SLAM layer's lifelong mode: thinning the graph of a kind of body to the places it needs (slam_graph.hpp,
// maybe_thin / thin; the choice of keyframes is estimators/keyframe/keyframe_thinning.hpp).
#include "estimators/slam/slam_graph.hpp"

#include "estimators/keyframe/keyframe_thinning.hpp"
#include "estimators/lie/pose_covariance.hpp"
#include "estimators/slam/pose_factors.hpp"

#include <algorithm>
#include <stdexcept>
#include <chrono>

namespace sextant::slam {

void SlamGraph::maybe_thin(bool planar, SlamListener& listener) {
  if (!options_.lifelong.enabled) return;
  // Over the budget, and a quarter of it added since the last thinning (a map whose places alone exceed the budget
  // is thinned at that pace rather than at every keyframe).
  int64_t& since = keyframes_since_thinning_[planar ? 1 : 0];
  ++since;
  int64_t in_graph = 0;
  for (const auto& [name, b] : bodies_)
    if (b.planar == planar) in_graph += static_cast<int64_t>(b.track.keyframes().size());
  const int budget = options_.lifelong.budget(planar).max_keyframes;
  if (in_graph <= budget || since < std::max(1, budget / 4)) return;
  since = 0;
  // Which keyframes stay is read off the estimate, and the rebuilt smoother starts from it: solved first when
  // updates are owed (apply_all's batch, the solve period).
  if (owes()) run_deferred(listener);
  thin(planar, listener);
}

// What one thinning keeps and builds, filled step by step by thin().
struct SlamGraph::ThinningPlan {
  ThinningPlan(bool planar_kind, graph::IncrementalSmoother& smoother, const std::vector<FactorTag>& factor_tags)
      : planar(planar_kind),
        kind(planar_kind ? 1 : 0),
        old(smoother),
        vars(smoother.graph().variables()),
        factors(smoother.graph().factors()),
        tags(factor_tags) {}
  bool planar;
  int kind;  // smoothers_[kind]
  graph::IncrementalSmoother& old;
  const std::vector<graph::Variable>& vars;
  const std::vector<std::unique_ptr<graph::Factor>>& factors;
  const std::vector<FactorTag>& tags;
  std::vector<char> keep_var;  // by old variable index
  // Per body of this kind, in the bodies' (name) order, by keyframe.  Not a map keyed by the Body's address: the
  // order in which the new smoother gets each body's factors would follow the addresses, and so would the last bits
  // of its estimates and the order of a fleet's thinning contributions, from run to run.
  std::vector<std::pair<Body*, std::vector<char>>> keep_of;
  const std::vector<char>& keep_of_body(const Body* b) const {
    const auto it = std::find_if(keep_of.begin(), keep_of.end(), [&](const auto& k) { return k.first == b; });
    if (it == keep_of.end()) throw std::logic_error("thinning: a body of the frame has no keyframe plan");
    return it->second;
  }
  std::vector<char> keep_factor;  // loops and sightings that stay (odometry is recomposed)
  std::vector<char> anchor;       // by old variable index: the keyframes that hold a frame's gauge
  int window = 0;                 // each body's newest keyframes that stay whole
  std::unique_ptr<graph::IncrementalSmoother> fresh;
  std::vector<FactorTag> fresh_tags;
  std::vector<int> remap;  // old variable index -> new, -1 when it leaves
  struct BodyPlan {
    Body* body;
    std::vector<TrackKeyframe> keyframes;
    std::vector<ThinnedKeyframe> thinned;
  };
  std::vector<BodyPlan> plans;
  int64_t thinned_count = 0;
};

void SlamGraph::thin(bool planar, SlamListener& listener) {
  const auto started = std::chrono::steady_clock::now();
  const int kind = planar ? 1 : 0;
  graph::IncrementalSmoother& old = *smoothers_[kind];
  ThinningPlan p(planar, old, factor_tags_[kind]);
  if (p.tags.size() != p.factors.size()) return;  // cannot happen: every factor goes through add_factor
  if (!choose_kept_keyframes(p)) return;
  choose_kept_factors(p);
  choose_anchors(p);
  try {
    rebuild_smoother(p);
  } catch (const std::invalid_argument&) {
    ++counters_.thinning_failures;
    return;
  }
  // The new graph's estimates are the old one's solution, so its factorization need not be built before it takes
  // over: spread over the next updates (which only work on it meanwhile, the estimates standing), the thinning costs
  // an update, not a spike.  Without spreading, it is solved now, and a failure keeps the old graph.
  const auto solve_started = std::chrono::steady_clock::now();
  const bool spread = p.fresh->begin_spread_build(&old);
  const graph::IncrementalStatus st = spread ? graph::IncrementalStatus{} : p.fresh->update();
  counters_.thinning_solve_us_last =
      std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - solve_started).count();
  if (!st.ok) {
    ++counters_.thinning_failures;
    return;
  }
  for (const auto& plan : p.plans) {
    if (plan.body->remote || plan.thinned.empty()) continue;
    KeyframesThinned t;
    for (const ThinnedKeyframe& k : plan.thinned) t.keyframes.push_back(k.id);
    for (const auto& [name, b] : bodies_)
      if (&b == plan.body) listener.contributed({name, std::move(t)});
  }
  commit_thinning(p);
  counters_.thinning_us_last =
      std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - started).count();
  counters_.thinning_us_max = std::max(counters_.thinning_us_max, counters_.thinning_us_last);
  factor_tags_[kind] = std::move(p.fresh_tags);
}

std::vector<char> SlamGraph::owner_kept(const Body& b) const {
  std::vector<char> keep(b.track.keyframes().size(), 1);
  for (size_t i = 0; i + 1 < keep.size(); ++i) keep[i] = b.owner_thinned.contains(b.track.keyframes()[i].id) ? 0 : 1;
  return keep;
}

// 1. Which keyframes stay, per body of this kind; false when all do.
bool SlamGraph::choose_kept_keyframes(ThinningPlan& p) {
  p.keep_var.assign(p.vars.size(), 1);
  bool any = false;
  // The window is the kind's, shared by its bodies: a fleet of N keeps each body's window/N newest keyframes whole,
  // so that the graph returns under its budget whatever the fleet's size.
  const int bodies = static_cast<int>(
      std::count_if(bodies_.begin(), bodies_.end(), [&](const auto& x) { return x.second.planar == p.planar; }));
  for (auto& [name, b] : bodies_) {
    if (b.planar != p.planar || b.track.empty()) continue;
    std::vector<ThinningCandidate> candidates;
    candidates.reserve(b.track.keyframes().size());
    for (const auto& k : b.track.keyframes())
      candidates.push_back({k.id, p.vars[static_cast<size_t>(k.variable)].as_se3()});
    KeyframeThinningOptions thinning = options_.lifelong.thinning;
    thinning.window = std::max(1, options_.lifelong.budget(p.planar).window / std::max(bodies, 1));
    p.window = thinning.window;
    auto keep = b.remote ? owner_kept(b) : keyframes_to_keep(candidates, p.planar, thinning);
    for (size_t i = 0; i < keep.size(); ++i)
      if (!keep[i]) p.keep_var[static_cast<size_t>(b.track.keyframes()[i].variable)] = 0, any = true;
    p.keep_of.emplace_back(&b, std::move(keep));
  }
  return any;
}

// 2. Which factors stay: loops and sightings whose variables all stay; odometry is recomposed below.  A landmark
//    without a sighting left leaves too.
void SlamGraph::choose_kept_factors(ThinningPlan& p) {
  p.keep_factor.assign(p.factors.size(), 0);
  std::vector<int> sightings_left(p.vars.size(), 0);
  for (size_t f = 0; f < p.factors.size(); ++f) {
    if (p.tags[f].role == FactorRole::kOdometry) continue;
    bool all = true;
    for (int v : p.factors[f]->variables()) all = all && p.keep_var[static_cast<size_t>(v)];
    p.keep_factor[f] = all ? 1 : 0;
    if (all && p.tags[f].role == FactorRole::kSighting)
      ++sightings_left[static_cast<size_t>(p.factors[f]->variables()[1])];
  }
  std::vector<char> is_landmark(p.vars.size(), 0);
  for (auto& [name, b] : bodies_)
    if (b.planar == p.planar)
      for (const auto& [id, l] : b.landmarks) is_landmark[static_cast<size_t>(l.variable)] = 1;
  for (size_t v = 0; v < p.vars.size(); ++v)
    if (is_landmark[v] && sightings_left[v] == 0) p.keep_var[v] = 0;
}

// 3. Which keyframe holds each frame's gauge in the thinned graph.  Its root body's first keyframe when the loops and
//    sightings that stay tie it to the map (residual rows at least twice its dimension: its own measurements
//    determine it), or always without LifelongOptions::hold_frame.  Else the settled keyframe (kept, older than its
//    body's window) of the frame with the most such rows, fixed where the whole graph's estimate has it now.  A first
//    keyframe that saw little is tied to the map, once its neighbours are thinned, by one composed odometry edge,
//    and a frame held by it is re-estimated from that edge: on MRCLAM's five robots the first thinning turned the
//    map 15 degrees about it, and every pose published after it with the map.  Held by a keyframe of the window
//    instead, the frame follows that keyframe's estimate of the moment, and later loops that correct it move the
//    old map (simulated 60-minute runs: up to 1.9 degrees, ATE 0.2-0.5 m against 0.014-0.026).
void SlamGraph::choose_anchors(ThinningPlan& p) {
  p.anchor.assign(p.vars.size(), 0);
  std::vector<int> rows(p.vars.size(), 0);  // residual rows of the loops and sightings that stay, per variable
  for (size_t f = 0; f < p.factors.size(); ++f)
    if (p.keep_factor[f])
      for (int v : p.factors[f]->variables()) rows[static_cast<size_t>(v)] += p.factors[f]->residual_dim();
  std::map<std::string, int> anchor;  // frame -> its anchor
  for (auto& [name, b] : bodies_)
    if (b.planar == p.planar && b.frame == name && !b.track.empty()) {
      int& best = anchor[name];
      best = b.track.keyframes().front().variable;
      if (!options_.lifelong.hold_frame ||
          rows[static_cast<size_t>(best)] >= 2 * p.vars[static_cast<size_t>(best)].dim())
        continue;
      for (auto& [other, o] : bodies_) {
        if (o.frame != name || o.track.empty()) continue;
        const auto& kf = o.track.keyframes();
        const std::vector<char>& keep = p.keep_of_body(&o);
        const size_t settled =
            kf.size() > static_cast<size_t>(p.window) ? kf.size() - static_cast<size_t>(p.window) : 0;
        for (size_t i = 0; i < settled; ++i) {
          const auto v = static_cast<size_t>(kf[i].variable);
          if (keep[i] && rows[v] > rows[static_cast<size_t>(best)]) best = kf[i].variable;
        }
      }
    }
  for (const auto& [frame, v] : anchor) p.anchor[static_cast<size_t>(v)] = 1;
}

// 4.-6. The new smoother: the variables that stay at their current estimates, in the old order; per body the kept
// keyframes with their odometry edges composed across the thinned ones (and the thinned records); the loops and
// sightings that stay, in their old order, with their kernels.  Throws std::invalid_argument when a factor cannot
// enter it.
void SlamGraph::rebuild_smoother(ThinningPlan& p) {
  p.fresh = std::make_unique<graph::IncrementalSmoother>(p.old.options());
  p.remap.assign(p.vars.size(), -1);
  for (size_t v = 0; v < p.vars.size(); ++v) {
    if (!p.keep_var[v]) continue;
    graph::Variable x = p.vars[v];
    if (x.is_pose()) x.fixed = p.anchor[v] != 0;
    p.remap[v] = p.fresh->add_variable(x);
  }
  for (auto& [b, keep] : p.keep_of) {
    ThinningPlan::BodyPlan plan{b, {}, {}};
    SE3 edge;
    Matrix6d covariance = Matrix6d::Zero();
    bool spanning = false;  // thinned keyframes since the last kept one
    const auto& keyframes = b->track.keyframes();
    for (size_t i = 0; i < keyframes.size(); ++i) {
      const TrackKeyframe& k = keyframes[i];
      if (i > 0) {
        covariance = compose_covariance(covariance, k.edge, k.edge_covariance);
        edge = edge * k.edge;
      }
      if (!keep[i]) {
        const SE3 at = p.vars[static_cast<size_t>(k.variable)].as_se3();
        plan.thinned.push_back({k.id, k.utime, k.odom, place_of(at, p.planar, options_.lifelong.thinning)});
        spanning = true;
        continue;
      }
      TrackKeyframe node = k;
      node.variable = p.remap[static_cast<size_t>(k.variable)];
      if (i > 0) {
        if (spanning) node.edge = edge, node.edge_covariance = covariance;
        auto f =
            odometry_factor(p.planar, plan.keyframes.back().variable, node.variable, node.edge, node.edge_covariance);
        if (!f) throw std::invalid_argument("composed odometry covariance cannot be inverted");
        p.fresh->add_factor(std::move(f), false);
        p.fresh_tags.push_back({FactorRole::kOdometry, false, std::nullopt});
      }
      plan.keyframes.push_back(std::move(node));
      edge = SE3();
      covariance.setZero();
      spanning = false;
    }
    p.thinned_count += static_cast<int64_t>(plan.thinned.size());
    p.plans.push_back(std::move(plan));
  }
  for (size_t f = 0; f < p.factors.size(); ++f) {
    if (!p.keep_factor[f]) continue;
    std::vector<int> vs;
    for (int v : p.factors[f]->variables()) vs.push_back(p.remap[static_cast<size_t>(v)]);
    p.fresh->add_factor(p.factors[f]->rebind(vs), p.tags[f].robust, p.tags[f].kernel_width);
    p.fresh_tags.push_back(p.tags[f]);
  }
}

// 7. Commit: the counters, the bodies' tracks and landmarks on the new variables, the new smoother in place.
void SlamGraph::commit_thinning(ThinningPlan& p) {
  for (size_t f = 0; f < p.factors.size(); ++f) {
    if (p.keep_factor[f] || p.tags[f].role == FactorRole::kOdometry) continue;
    if (p.tags[f].role == FactorRole::kLoop)
      ++counters_.loops_thinned;
    else
      ++counters_.sightings_thinned;
  }
  for (auto& plan : p.plans) {
    Body& b = *plan.body;
    b.track.replace_keyframes(std::move(plan.keyframes), plan.thinned);
    for (const ThinnedKeyframe& k : plan.thinned) b.owner_thinned.erase(k.id);
    for (auto it = b.landmarks.begin(); it != b.landmarks.end();) {
      const int v = p.remap[static_cast<size_t>(it->second.variable)];
      if (v < 0) {
        ++counters_.landmarks_thinned;
        it = b.landmarks.erase(it);
      } else {
        it->second.variable = v;
        ++it;
      }
    }
    b.smoother = p.fresh.get();
  }
  counters_.keyframes_thinned += p.thinned_count;
  ++counters_.thinnings;
  smoothers_[p.kind] = std::move(p.fresh);
  // The gates' marginals move to the variables' new indices: the estimates did not change, and while the new
  // factorization is being built there is no other.  (A thinned graph holds less information, so they are a little
  // narrower than its own until they age out after kGateMarginalUpdates updates.)
  std::map<int, std::pair<int64_t, Eigen::MatrixXd>> moved;
  for (auto& [v, m] : gate_marginals_[p.kind])
    if (const int to = p.remap[static_cast<size_t>(v)]; to >= 0) moved.emplace(to, std::move(m));
  gate_marginals_[p.kind] = std::move(moved);
}

}  // namespace sextant::slam
