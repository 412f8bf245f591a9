// The graph stage's state: saved to and restored from the state directory (graph_stage.hpp, save/load; README "State
// directory"), and a body forgotten with its map (forget).
#include "daemon/engine/event_archive.hpp"
#include "daemon/engine/graph_stage.hpp"
#include "estimators/graph/graph_archive.hpp"

#include <algorithm>
#include <stdexcept>

namespace sextant::engine {

std::vector<int64_t*> GraphStage::saved_counters() {
  return {&keyframes_,          &keyframes_rejected_,     &keyframes_reanchored_,  &requests_,
          &loops_accepted_,     &loops_rejected_,         &loops_unmatched_,       &loops_unknown_source_,
          &optimizer_failures_, &rebuilds_,               &relinearized_,          &out_of_order_,
          &bad_edges_,          &landmarks_,              &sightings_accepted_,    &sightings_rejected_,
          &sightings_without_id_, &sightings_unknown_source_, &sightings_before_keyframe_, &sightings_unmatched_,
          &sightings_malformed_, &sightings_dropped_,     &trajectory_messages_,   &trajectory_bytes_,
          &updates_,            &thinnings_,              &thinning_failures_,     &keyframes_thinned_,
          &loops_thinned_,      &sightings_thinned_,      &landmarks_thinned_,     &loops_on_thinned_};
}

void GraphStage::save(archive::ArchiveWriter& w) {
  w(next_variable_id_)(next_request_id_)(keyframes_since_thinning_[0])(keyframes_since_thinning_[1]);
  for (int64_t* c : saved_counters()) w(*c);
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
  for (const auto& [source, b] : bodies_) {
    w(source)(b.planar)(b.selector)(b.last_utime)(b.last_odom)(b.last_odom_covariance)(b.since_keyframe);
    w(static_cast<uint64_t>(b.keyframes.size()));
    for (const KeyframeNode& k : b.keyframes)
      w(k.id)(k.utime)(k.variable)(k.odom)(k.odom_covariance)(k.edge_covariance)(k.edge);
    w(static_cast<uint64_t>(b.thinned.size()));
    for (const ThinnedKeyframe& k : b.thinned) w(k.id)(k.utime)(k.odom);
    w(b.next_keyframe_id)(b.odometry)(b.early_loops)(b.early_sightings);
    w(static_cast<uint64_t>(b.landmarks.size()));
    for (const auto& [id, l] : b.landmarks) w(id)(l.variable)(l.sightings);
    w(b.feed)(b.newest_utime)(corrections_->get(source));
  }
  // The canonical form both this stage and a restored one continue from (graph_stage.hpp, save).
  for (int kind = 0; kind < 2; ++kind) {
    if (smoothers_[kind]) rebuilds_ += smoothers_[kind]->rebuild().ok ? 1 : 0;
    gate_marginals_[kind].clear();
  }
}

void GraphStage::load(archive::ArchiveReader& r) {
  if (!bodies_.empty() || smoothers_[0] || smoothers_[1]) throw std::logic_error("GraphStage::load into a used stage");
  r(next_variable_id_)(next_request_id_)(keyframes_since_thinning_[0])(keyframes_since_thinning_[1]);
  for (int64_t* c : saved_counters()) r(*c);
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
    const auto source = r.get<std::string>();
    Body b;
    r(b.planar);
    KeyframeSelectorOptions ko = config_.keyframes;
    ko.planar = b.planar;
    b.selector = KeyframeSelector(ko);
    r(b.selector)(b.last_utime)(b.last_odom)(b.last_odom_covariance)(b.since_keyframe);
    b.smoother = &smoother_for(b.planar);
    const int variables = static_cast<int>(b.smoother->graph().variables().size());
    const auto check_variable = [&](int v, bool pose) {
      if (v < 0 || v >= variables || b.smoother->graph().variables()[static_cast<size_t>(v)].is_pose() != pose)
        r.fail("body '" + source + "': variable " + std::to_string(v) + " is not a " + (pose ? "pose" : "point") +
               " of its graph");
    };
    const uint64_t keyframes = r.count(1, "the keyframes");
    for (uint64_t k = 0; k < keyframes; ++k) {
      KeyframeNode node;
      r(node.id)(node.utime)(node.variable)(node.odom)(node.odom_covariance)(node.edge_covariance)(node.edge);
      check_variable(node.variable, true);
      b.by_utime[node.utime] = b.keyframes.size();
      b.keyframes.push_back(std::move(node));
    }
    const uint64_t thinned = r.count(1, "the thinned keyframes");
    for (uint64_t k = 0; k < thinned; ++k) {
      ThinnedKeyframe t;
      r(t.id)(t.utime)(t.odom);
      b.thinned.push_back(t);
    }
    r(b.next_keyframe_id)(b.odometry)(b.early_loops)(b.early_sightings);
    const uint64_t landmarks = r.count(1, "the landmarks");
    for (uint64_t k = 0; k < landmarks; ++k) {
      const auto id = r.get<int64_t>();
      Body::Landmark l;
      r(l.variable)(l.sightings);
      check_variable(l.variable, false);
      b.landmarks[id] = l;
    }
    b.feed = TrajectoryFeed(config_.trajectory);
    r(b.feed)(b.newest_utime);
    if (const auto c = r.get<std::optional<GraphCorrection>>()) corrections_->set(source, *c);
    if (!bodies_.emplace(source, std::move(b)).second) r.fail("body '" + source + "' twice");
  }
}

void GraphStage::forget(const std::string& source) {
  auto it = bodies_.find(source);
  if (it == bodies_.end()) return;
  const bool planar = it->second.planar;
  const int kind = planar ? 1 : 0;
  const graph::IncrementalSmoother& old = *smoothers_[kind];
  const auto& vars = old.graph().variables();
  const auto& factors = old.graph().factors();
  std::vector<char> drop(vars.size(), 0);
  for (const auto& k : it->second.keyframes) drop[static_cast<size_t>(k.variable)] = 1;
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
  corrections_->erase(source);
  bodies_.erase(it);
  bool others = false;
  for (auto& [name, b] : bodies_) {
    if (b.planar != planar) continue;
    others = true;
    for (auto& k : b.keyframes) k.variable = remap[static_cast<size_t>(k.variable)];
    for (auto& [id, l] : b.landmarks) l.variable = remap[static_cast<size_t>(l.variable)];
    b.smoother = fresh.get();
  }
  gate_marginals_[kind].clear();
  if (!others) {
    smoothers_[kind].reset();
    factor_tags_[kind].clear();
    return;
  }
  if (!fresh->update().ok) ++optimizer_failures_;
  smoothers_[kind] = std::move(fresh);
  factor_tags_[kind] = std::move(fresh_tags);
}

}  // namespace sextant::engine
