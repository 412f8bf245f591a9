// The SLAM layer's state: saved to and restored from a binary archive (slam_graph.hpp, save/load), and a body
// forgotten with its map (forget).
#include "estimators/graph/graph_archive.hpp"
#include "estimators/slam/slam_graph.hpp"

#include <algorithm>
#include <stdexcept>

namespace sextant::slam {

void SlamGraph::save(archive::ArchiveWriter& w) {
  w(next_variable_id_)(keyframes_since_thinning_[0])(keyframes_since_thinning_[1]);
  SlamCounters::saved(w, counters_);
  for (int kind = 0; kind < 2; ++kind) {
    const graph::IncrementalSmoother* s = smoothers_[kind].get();
    w(s != nullptr);
    if (s == nullptr) continue;
    w(s->graph().variables());
    const auto& factors = s->graph().factors();
    w(static_cast<uint64_t>(factors.size()));
    for (size_t f = 0; f < factors.size(); ++f) {
      graph::save_factor(w, *factors[f]);
      const FactorTag& t = factor_tags_[kind][f];
      w(t.role)(t.robust)(t.kernel_width);
    }
  }
  w(static_cast<uint64_t>(bodies_.size()));
  for (const auto& [name, b] : bodies_) {
    w(name)(b.planar)(b.selector)(b.track)(b.early_loops)(b.early_sightings);
    w(static_cast<uint64_t>(b.landmarks.size()));
    for (const auto& [id, l] : b.landmarks) w(id)(l.variable)(l.sightings);
  }
  // The canonical form both this layer and a restored one continue from (slam_graph.hpp, save).
  for (int kind = 0; kind < 2; ++kind) {
    if (smoothers_[kind]) counters_.rebuilds += smoothers_[kind]->rebuild().ok ? 1 : 0;
    gate_marginals_[kind].clear();
  }
}

void SlamGraph::load(archive::ArchiveReader& r) {
  if (!bodies_.empty() || smoothers_[0] || smoothers_[1]) throw std::logic_error("SlamGraph::load into a used layer");
  r(next_variable_id_)(keyframes_since_thinning_[0])(keyframes_since_thinning_[1]);
  SlamCounters::saved(r, counters_);
  for (int kind = 0; kind < 2; ++kind) {
    if (!r.get<bool>()) continue;
    graph::IncrementalSmoother& s = smoother_for(kind == 1);
    try {
      for (const graph::Variable& v : r.get<std::vector<graph::Variable>>()) s.add_variable(v);
      const uint64_t n = r.count(1, "the graph's factors");
      for (uint64_t f = 0; f < n; ++f) {
        std::unique_ptr<graph::Factor> factor = graph::load_factor(r);
        FactorTag t;
        r(t.role)(t.robust)(t.kernel_width);
        if (t.role != FactorRole::kOdometry && t.role != FactorRole::kLoop && t.role != FactorRole::kSighting)
          r.fail("a factor of unknown role");
        s.add_factor(std::move(factor), t.robust, t.kernel_width);
        factor_tags_[kind].push_back(t);
      }
    } catch (const std::invalid_argument& e) {  // the smoother's own checks: an index out of range, a bad information
      r.fail(std::string("graph: ") + e.what());
    }
    s.rebuild();
  }
  const uint64_t bodies = r.count(1, "the bodies");
  for (uint64_t i = 0; i < bodies; ++i) {
    const auto name = r.get<std::string>();
    Body b;
    r(b.planar);
    KeyframeSelectorOptions ko = options_.keyframes;
    ko.planar = b.planar;
    b.selector = KeyframeSelector(ko);
    r(b.selector)(b.track)(b.early_loops)(b.early_sightings);
    b.smoother = &smoother_for(b.planar);
    const int variables = static_cast<int>(b.smoother->graph().variables().size());
    const auto check_variable = [&](int v, bool pose) {
      if (v < 0 || v >= variables || b.smoother->graph().variables()[static_cast<size_t>(v)].is_pose() != pose)
        r.fail("body '" + name + "': variable " + std::to_string(v) + " is not a " + (pose ? "pose" : "point") +
               " of its graph");
    };
    for (const TrackKeyframe& k : b.track.keyframes()) check_variable(k.variable, true);
    const uint64_t landmarks = r.count(1, "the landmarks");
    for (uint64_t k = 0; k < landmarks; ++k) {
      const auto id = r.get<int64_t>();
      Landmark l;
      r(l.variable)(l.sightings);
      check_variable(l.variable, false);
      b.landmarks[id] = l;
    }
    counters_.loops_waiting += static_cast<int64_t>(b.early_loops.size());
    if (!bodies_.emplace(name, std::move(b)).second) r.fail("body '" + name + "' twice");
  }
}

void SlamGraph::forget(const std::string& name) {
  auto it = bodies_.find(name);
  if (it == bodies_.end()) return;
  const bool planar = it->second.planar;
  const int kind = planar ? 1 : 0;
  const graph::IncrementalSmoother& old = *smoothers_[kind];
  const auto& vars = old.graph().variables();
  const auto& factors = old.graph().factors();
  std::vector<char> drop(vars.size(), 0);
  for (const auto& k : it->second.track.keyframes()) drop[static_cast<size_t>(k.variable)] = 1;
  for (const auto& [id, l] : it->second.landmarks) drop[static_cast<size_t>(l.variable)] = 1;
  // Bodies share no variable: the other bodies' variables and factors make the new smoother, in their old order.
  auto fresh = std::make_unique<graph::IncrementalSmoother>(old.options());
  std::vector<FactorTag> fresh_tags;
  std::vector<int> remap(vars.size(), -1);
  for (size_t v = 0; v < vars.size(); ++v)
    if (!drop[v]) remap[v] = fresh->add_variable(vars[v]);
  for (size_t f = 0; f < factors.size(); ++f) {
    std::vector<int> vs;
    for (int v : factors[f]->variables()) vs.push_back(remap[static_cast<size_t>(v)]);
    if (std::find(vs.begin(), vs.end(), -1) != vs.end()) continue;
    const FactorTag& t = factor_tags_[kind][f];
    fresh->add_factor(factors[f]->rebind(vs), t.robust, t.kernel_width);
    fresh_tags.push_back(t);
  }
  counters_.loops_waiting -= static_cast<int64_t>(it->second.early_loops.size());
  bodies_.erase(it);
  bool others = false;
  for (auto& [other, b] : bodies_) {
    if (b.planar != planar) continue;
    others = true;
    b.track.remap_variables(remap);
    for (auto& [id, l] : b.landmarks) l.variable = remap[static_cast<size_t>(l.variable)];
    b.smoother = fresh.get();
  }
  gate_marginals_[kind].clear();
  if (!others) {
    smoothers_[kind].reset();
    factor_tags_[kind].clear();
    return;
  }
  if (!fresh->update().ok) ++counters_.optimizer_failures;
  smoothers_[kind] = std::move(fresh);
  factor_tags_[kind] = std::move(fresh_tags);
}

}  // namespace sextant::slam
