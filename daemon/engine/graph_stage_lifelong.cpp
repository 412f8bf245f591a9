// Lifelong mode of the graph stage: thinning the graph to the places it needs (graph_stage.hpp, maybe_thin/thin).
#include "daemon/engine/graph_stage.hpp"
#include "daemon/engine/pose_covariance.hpp"

#include <algorithm>
#include <chrono>

namespace sextant::engine {

int64_t GraphStage::graph_keyframes() const {
  int64_t n = 0;
  for (const auto& [source, b] : bodies_) n += static_cast<int64_t>(b.keyframes.size());
  return n;
}

int64_t GraphStage::graph_landmarks() const {
  int64_t n = 0;
  for (const auto& [source, b] : bodies_) n += static_cast<int64_t>(b.landmarks.size());
  return n;
}

int64_t GraphStage::graph_factors() const {
  int64_t n = 0;
  for (const auto& s : smoothers_)
    if (s) n += static_cast<int64_t>(s->graph().factors().size());
  return n;
}

void GraphStage::maybe_thin(bool planar) {
  if (!config_.lifelong.enabled) return;
  // Over the budget, and a quarter of it added since the last thinning (a map whose places alone exceed the budget
  // is thinned at that pace rather than at every keyframe).
  int64_t& since = keyframes_since_thinning_[planar ? 1 : 0];
  ++since;
  int64_t in_graph = 0;
  for (const auto& [source, b] : bodies_)
    if (b.planar == planar) in_graph += static_cast<int64_t>(b.keyframes.size());
  const int budget = config_.lifelong.budget(planar).max_keyframes;
  if (in_graph <= budget || since < std::max(1, budget / 4)) return;
  since = 0;
  thin(planar);
}

void GraphStage::thin(bool planar) {
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
  for (auto& [source, b] : bodies_) {
    if (b.planar != planar || b.keyframes.empty()) continue;
    std::vector<ThinningCandidate> candidates;
    candidates.reserve(b.keyframes.size());
    for (const auto& k : b.keyframes) candidates.push_back({k.id, vars[static_cast<size_t>(k.variable)].as_se3()});
    KeyframeThinningOptions thinning = config_.lifelong.thinning;
    thinning.window = config_.lifelong.budget(planar).window;
    auto keep = keyframes_to_keep(candidates, planar, thinning);
    for (size_t i = 0; i < keep.size(); ++i)
      if (!keep[i]) keep_var[static_cast<size_t>(b.keyframes[i].variable)] = 0, any = true;
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
  for (auto& [source, b] : bodies_)
    if (b.planar == planar)
      for (const auto& [id, l] : b.landmarks) is_landmark[static_cast<size_t>(l.variable)] = 1;
  for (size_t v = 0; v < vars.size(); ++v)
    if (is_landmark[v] && sightings_left[v] == 0) keep_var[v] = 0;

  // 3. The new smoother: the variables that stay at their current estimates, in the old order.
  graph::IncrementalOptions options = old.options();
  auto fresh = std::make_unique<graph::IncrementalSmoother>(options);
  std::vector<FactorTag> fresh_tags;
  std::vector<int> remap(vars.size(), -1);
  for (size_t v = 0; v < vars.size(); ++v)
    if (keep_var[v]) remap[v] = fresh->add_variable(vars[v]);

  // 4. Per body: the kept keyframes, their odometry edges composed across the thinned ones, and the thinned records.
  struct BodyPlan {
    Body* body;
    std::vector<KeyframeNode> keyframes;
    std::vector<ThinnedKeyframe> thinned;
  };
  std::vector<BodyPlan> plans;
  int64_t thinned_count = 0;
  try {
    for (auto& [b, keep] : keep_of) {
      BodyPlan plan{b, {}, {}};
      SE3 edge;
      Matrix6 covariance = Matrix6::Zero();
      bool spanning = false;  // thinned keyframes since the last kept one
      for (size_t i = 0; i < b->keyframes.size(); ++i) {
        const KeyframeNode& k = b->keyframes[i];
        if (i > 0) {
          covariance = compose_covariance(covariance, k.edge, k.edge_covariance);
          edge = edge * k.edge;
        }
        if (!keep[i]) {
          plan.thinned.push_back({k.id, k.utime, k.odom});
          spanning = true;
          continue;
        }
        KeyframeNode node = k;
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
    ++thinning_failures_;
    return;
  }
  const auto solve_started = std::chrono::steady_clock::now();
  const graph::IncrementalStatus st = fresh->update();
  thinning_solve_us_ = std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - solve_started).count();
  if (!st.ok) {
    ++thinning_failures_;  // the old graph stays
    return;
  }

  // 6. Commit.
  for (size_t f = 0; f < factors.size(); ++f) {
    if (keep_factor[f] || tags[f].role == FactorRole::kOdometry) continue;
    if (tags[f].role == FactorRole::kLoop) ++loops_thinned_;
    else ++sightings_thinned_;
  }
  for (auto& plan : plans) {
    Body& b = *plan.body;
    b.keyframes = std::move(plan.keyframes);
    b.by_utime.clear();
    for (size_t i = 0; i < b.keyframes.size(); ++i) b.by_utime[b.keyframes[i].utime] = i;
    // Thinned keyframes stay in time order (they were thinned from older to newer, and each thinning's are newer
    // than the previous one's oldest survivors, so merge).
    std::vector<ThinnedKeyframe> merged;
    merged.reserve(b.thinned.size() + plan.thinned.size());
    std::merge(b.thinned.begin(), b.thinned.end(), plan.thinned.begin(), plan.thinned.end(), std::back_inserter(merged),
               [](const ThinnedKeyframe& x, const ThinnedKeyframe& y) { return x.utime < y.utime; });
    b.thinned = std::move(merged);
    // Bounded for unbounded time: the oldest records go first (a loop about such a time is then counted unmatched).
    if (b.thinned.size() > kMaxThinnedRecords)
      b.thinned.erase(b.thinned.begin(), b.thinned.end() - static_cast<std::ptrdiff_t>(kMaxThinnedRecords));
    for (auto it = b.landmarks.begin(); it != b.landmarks.end();) {
      const int v = remap[static_cast<size_t>(it->second.variable)];
      if (v < 0) {
        ++landmarks_thinned_;
        it = b.landmarks.erase(it);
      } else {
        it->second.variable = v;
        ++it;
      }
    }
    b.smoother = fresh.get();
  }
  keyframes_thinned_ += thinned_count;
  ++thinnings_;
  smoothers_[kind] = std::move(fresh);
  gate_marginals_[kind].clear();  // the variables' indices changed
  thinning_us_ = std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - started).count();
  thinning_us_max_ = std::max(thinning_us_max_, thinning_us_);
  factor_tags_[kind] = std::move(fresh_tags);
}

}  // namespace sextant::engine
