// The SLAM layer's lifelong mode: thinning the graph of a kind of body to the places it needs (slam_graph.hpp,
// maybe_thin / thin; the choice of keyframes is estimators/keyframe/keyframe_thinning.hpp).
#include "estimators/slam/slam_graph.hpp"

#include "estimators/keyframe/keyframe_thinning.hpp"
#include "estimators/lie/pose_covariance.hpp"
#include "estimators/slam/pose_factors.hpp"

#include <algorithm>
#include <chrono>

namespace sextant::slam {

void SlamGraph::maybe_thin(bool planar) {
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
  thin(planar);
}

void SlamGraph::thin(bool planar) {
  const auto started = std::chrono::steady_clock::now();
  const int kind = planar ? 1 : 0;
  graph::IncrementalSmoother& old = *smoothers_[kind];
  const auto& vars = old.graph().variables();
  const auto& factors = old.graph().factors();
  const std::vector<FactorTag>& tags = factor_tags_[kind];
  if (tags.size() != factors.size()) return;  // cannot happen: every factor goes through add_factor

  // 1. Which keyframes stay, per body of this kind.
  std::vector<char> keep_var(vars.size(), 1);
  std::map<Body*, std::vector<char>> keep_of;
  bool any = false;
  for (auto& [name, b] : bodies_) {
    if (b.planar != planar || b.track.empty()) continue;
    std::vector<ThinningCandidate> candidates;
    candidates.reserve(b.track.keyframes().size());
    for (const auto& k : b.track.keyframes()) candidates.push_back({k.id, vars[static_cast<size_t>(k.variable)].as_se3()});
    KeyframeThinningOptions thinning = options_.lifelong.thinning;
    thinning.window = options_.lifelong.budget(planar).window;
    auto keep = keyframes_to_keep(candidates, planar, thinning);
    for (size_t i = 0; i < keep.size(); ++i)
      if (!keep[i]) keep_var[static_cast<size_t>(b.track.keyframes()[i].variable)] = 0, any = true;
    keep_of.emplace(&b, std::move(keep));
  }
  if (!any) return;

  // 2. Which factors stay: loops and sightings whose variables all stay; odometry is recomposed below.  A landmark
  //    without a sighting left leaves too.
  std::vector<char> keep_factor(factors.size(), 0);
  std::vector<int> sightings_left(vars.size(), 0);
  for (size_t f = 0; f < factors.size(); ++f) {
    if (tags[f].role == FactorRole::kOdometry) continue;
    bool all = true;
    for (int v : factors[f]->variables()) all = all && keep_var[static_cast<size_t>(v)];
    keep_factor[f] = all ? 1 : 0;
    if (all && tags[f].role == FactorRole::kSighting) ++sightings_left[static_cast<size_t>(factors[f]->variables()[1])];
  }
  std::vector<char> is_landmark(vars.size(), 0);
  for (auto& [name, b] : bodies_)
    if (b.planar == planar)
      for (const auto& [id, l] : b.landmarks) is_landmark[static_cast<size_t>(l.variable)] = 1;
  for (size_t v = 0; v < vars.size(); ++v)
    if (is_landmark[v] && sightings_left[v] == 0) keep_var[v] = 0;

  // 3. The new smoother: the variables that stay at their current estimates, in the old order.
  auto fresh = std::make_unique<graph::IncrementalSmoother>(old.options());
  std::vector<FactorTag> fresh_tags;
  std::vector<int> remap(vars.size(), -1);
  for (size_t v = 0; v < vars.size(); ++v)
    if (keep_var[v]) remap[v] = fresh->add_variable(vars[v]);

  // 4. Per body: the kept keyframes, their odometry edges composed across the thinned ones, and the thinned records.
  struct BodyPlan {
    Body* body;
    std::vector<TrackKeyframe> keyframes;
    std::vector<ThinnedKeyframe> thinned;
  };
  std::vector<BodyPlan> plans;
  int64_t thinned_count = 0;
  try {
    for (auto& [b, keep] : keep_of) {
      BodyPlan plan{b, {}, {}};
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
          plan.thinned.push_back({k.id, k.utime, k.odom});
          spanning = true;
          continue;
        }
        TrackKeyframe node = k;
        node.variable = remap[static_cast<size_t>(k.variable)];
        if (i > 0) {
          if (spanning) node.edge = edge, node.edge_covariance = covariance;
          auto f = odometry_factor(planar, plan.keyframes.back().variable, node.variable, node.edge, node.edge_covariance);
          if (!f) throw std::invalid_argument("composed odometry covariance cannot be inverted");
          fresh->add_factor(std::move(f), false);
          fresh_tags.push_back({FactorRole::kOdometry, false, std::nullopt});
        }
        plan.keyframes.push_back(std::move(node));
        edge = SE3();
        covariance.setZero();
        spanning = false;
      }
      thinned_count += static_cast<int64_t>(plan.thinned.size());
      plans.push_back(std::move(plan));
    }
    // 5. Loops and sightings that stay, in their old order, with their kernels.
    for (size_t f = 0; f < factors.size(); ++f) {
      if (!keep_factor[f]) continue;
      std::vector<int> vs;
      for (int v : factors[f]->variables()) vs.push_back(remap[static_cast<size_t>(v)]);
      fresh->add_factor(factors[f]->rebind(vs), tags[f].robust, tags[f].kernel_width);
      fresh_tags.push_back(tags[f]);
    }
  } catch (const std::invalid_argument&) {
    ++counters_.thinning_failures;
    return;
  }
  const auto solve_started = std::chrono::steady_clock::now();
  const graph::IncrementalStatus st = fresh->update();
  counters_.thinning_solve_us_last =
      std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - solve_started).count();
  if (!st.ok) {
    ++counters_.thinning_failures;  // the old graph stays
    return;
  }

  // 6. Commit.
  for (size_t f = 0; f < factors.size(); ++f) {
    if (keep_factor[f] || tags[f].role == FactorRole::kOdometry) continue;
    if (tags[f].role == FactorRole::kLoop) ++counters_.loops_thinned;
    else ++counters_.sightings_thinned;
  }
  for (auto& plan : plans) {
    Body& b = *plan.body;
    b.track.replace_keyframes(std::move(plan.keyframes), plan.thinned);
    for (auto it = b.landmarks.begin(); it != b.landmarks.end();) {
      const int v = remap[static_cast<size_t>(it->second.variable)];
      if (v < 0) {
        ++counters_.landmarks_thinned;
        it = b.landmarks.erase(it);
      } else {
        it->second.variable = v;
        ++it;
      }
    }
    b.smoother = fresh.get();
  }
  counters_.keyframes_thinned += thinned_count;
  ++counters_.thinnings;
  smoothers_[kind] = std::move(fresh);
  gate_marginals_[kind].clear();  // the variables' indices changed
  counters_.thinning_us_last =
      std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - started).count();
  counters_.thinning_us_max = std::max(counters_.thinning_us_max, counters_.thinning_us_last);
  factor_tags_[kind] = std::move(fresh_tags);
}

}  // namespace sextant::slam
