// The SLAM layer's state: saved to and restored from a binary archive (slam_graph.hpp, save/load), and a body
// forgotten with its map (forget).
#include "estimators/graph/graph_archive.hpp"
#include "estimators/slam/slam_graph.hpp"

#include <algorithm>
#include <stdexcept>

namespace sextant::slam {

void SlamGraph::save(archive::ArchiveWriter& w) {
  // The rebuild below solves what the solve period holds back (its reports are not made): both layers continue with
  // nothing owed and the same clock.
  deferred_ = Deferred{};
  for (auto& [name, b] : bodies_) b.reported = b.clock;
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
    w(name)(b.planar)(b.frame)(b.selector)(b.track)(b.early_loops)(b.early_sightings)(b.remote)(b.early_halves)(
        b.early_seen)(std::vector<int64_t>(b.owner_thinned.begin(), b.owner_thinned.end()))(b.clock)(b.reported);
    w(static_cast<uint64_t>(b.landmarks.size()));
    for (const auto& [id, l] : b.landmarks) w(id)(l.variable)(l.sightings);
  }
  w(static_cast<uint64_t>(pending_.sightings.size()));
  for (const SightingLink& s : pending_.sightings) SightingLink::fields(w, s);
  w(static_cast<uint64_t>(pending_.loops.size()));
  for (const LoopLink& l : pending_.loops) LoopLink::fields(w, l);
  w(waiting_wholes_);
  w(static_cast<uint64_t>(moved_frames_.size()));
  for (const auto& [gone, into] : moved_frames_) w(gone)(into.first)(into.second);
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
    r(b.planar)(b.frame);
    KeyframeSelectorOptions ko = options_.keyframes;
    ko.planar = b.planar;
    b.selector = KeyframeSelector(ko);
    r(b.selector)(b.track)(b.early_loops)(b.early_sightings)(b.remote)(b.early_halves)(b.early_seen);
    const auto thinned = r.get<std::vector<int64_t>>();
    b.owner_thinned = std::set<int64_t>(thinned.begin(), thinned.end());
    r(b.clock)(b.reported);
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
    counters_.loops_waiting += static_cast<int64_t>(b.early_loops.size() + b.early_halves.size());
    if (!bodies_.emplace(name, std::move(b)).second) r.fail("body '" + name + "' twice");
  }
  load_fleet(r);
}

void SlamGraph::load_fleet(archive::ArchiveReader& r) {
  for (const auto& [name, b] : bodies_) {
    const auto root = bodies_.find(b.frame);
    if (root == bodies_.end() || root->second.frame != b.frame || root->second.planar != b.planar)
      r.fail("body '" + name + "': its frame '" + b.frame + "' is not the root of a frame of its kind");
    if (b.frame != name && !b.landmarks.empty()) r.fail("body '" + name + "': landmarks outside its frame's root");
  }
  const auto known = [&](const std::string& body) {
    if (!bodies_.contains(body)) r.fail("a fleet link to an unknown body '" + body + "'");
  };
  for (uint64_t n = r.count(1, "the pending robot sightings"), k = 0; k < n; ++k) {
    SightingLink s;
    SightingLink::fields(r, s);
    known(s.observer), known(s.observed);
    pending_.sightings.push_back(std::move(s));
  }
  for (uint64_t n = r.count(1, "the pending inter-robot loops"), k = 0; k < n; ++k) {
    LoopLink l;
    LoopLink::fields(r, l);
    known(l.from), known(l.to);
    pending_.loops.push_back(std::move(l));
  }
  r(waiting_wholes_);
  for (const GraphContribution& c : waiting_wholes_)
    if (!std::holds_alternative<BodySighting>(c.what) && !std::holds_alternative<BodyLoop>(c.what) &&
        !std::holds_alternative<FrameJoin>(c.what))
      r.fail("a waiting contribution of body '" + c.body +
             "' that is not a robot sighting, an inter-robot loop or a join");
  for (uint64_t n = r.count(1, "the joined frames"), k = 0; k < n; ++k) {
    std::string gone, into;
    SE3 placement;
    r(gone)(into)(placement);
    if (!(into < gone)) r.fail("frame '" + gone + "' joined into '" + into + "', a later name");
    moved_frames_[gone] = {into, placement};
  }
}

SlamGraph::Rebuilt SlamGraph::rebuilt(int kind, const std::vector<graph::Variable>& vars,
                                      const std::vector<int>& merge_into) const {
  const graph::IncrementalSmoother& old = *smoothers_[kind];
  const auto& factors = old.graph().factors();
  Rebuilt r{std::make_unique<graph::IncrementalSmoother>(old.options()), {}, std::vector<int>(vars.size(), -1)};
  for (size_t v = 0; v < vars.size(); ++v)
    if (merge_into[v] == -1) r.remap[v] = r.smoother->add_variable(vars[v]);
  for (size_t v = 0; v < vars.size(); ++v)
    if (merge_into[v] >= 0) r.remap[v] = r.remap[static_cast<size_t>(merge_into[v])];
  for (size_t f = 0; f < factors.size(); ++f) {
    std::vector<int> vs;
    for (int v : factors[f]->variables()) vs.push_back(r.remap[static_cast<size_t>(v)]);
    if (std::find(vs.begin(), vs.end(), -1) != vs.end()) continue;
    const FactorTag& t = factor_tags_[kind][f];
    r.smoother->add_factor(factors[f]->rebind(vs), t.robust, t.kernel_width);
    r.tags.push_back(t);
  }
  return r;
}

void SlamGraph::commit_rebuilt(int kind, Rebuilt r) {
  for (auto& [name, b] : bodies_) {
    if ((b.planar ? 1 : 0) != kind) continue;
    b.track.remap_variables(r.remap);
    for (auto& [id, l] : b.landmarks) l.variable = r.remap[static_cast<size_t>(l.variable)];
    b.smoother = r.smoother.get();
  }
  smoothers_[kind] = std::move(r.smoother);
  factor_tags_[kind] = std::move(r.tags);
  gate_marginals_[kind].clear();  // the variables' indices changed
}

void SlamGraph::drop_unseen_landmarks(int kind, std::vector<int>& merge_into) {
  std::vector<int> seen(merge_into.size(), 0);
  for (const auto& f : smoothers_[kind]->graph().factors()) {
    bool stays = true;
    for (int v : f->variables()) stays = stays && merge_into[static_cast<size_t>(v)] != kDropVariable;
    if (stays)
      for (int v : f->variables()) ++seen[static_cast<size_t>(v)];
  }
  for (auto& [name, b] : bodies_) {
    if ((b.planar ? 1 : 0) != kind) continue;
    for (auto it = b.landmarks.begin(); it != b.landmarks.end();) {
      const auto v = static_cast<size_t>(it->second.variable);
      if (merge_into[v] == kDropVariable || seen[v] > 0) {
        ++it;
        continue;
      }
      merge_into[v] = kDropVariable;
      it = b.landmarks.erase(it);
    }
  }
}

std::string SlamGraph::hand_over_frame(const std::string& root) {
  Body& old = bodies_.at(root);
  if (old.frame != root) return {};
  std::string next;
  for (auto& [name, b] : bodies_)
    if (name != root && b.frame == root) {
      if (next.empty()) next = name;
      b.frame = next;
    }
  for (auto& [gone, into] : moved_frames_)
    if (into.first == root) into.first = next;  // empty when alone: such joins lead nowhere any more
  std::erase_if(moved_frames_, [&](const auto& m) { return m.second.first.empty() || m.first == next; });
  if (next.empty()) return next;  // alone: its landmarks leave with it
  bodies_.at(next).landmarks = std::move(old.landmarks);
  old.landmarks.clear();
  return next;
}

void SlamGraph::forget(const std::string& name) {
  auto it = bodies_.find(name);
  if (it == bodies_.end()) return;
  const bool planar = it->second.planar;
  const int kind = planar ? 1 : 0;
  moved_frames_.erase(name);
  const std::string frame = it->second.frame;
  const std::string next_root = hand_over_frame(name);
  std::vector<graph::Variable> vars = smoothers_[kind]->graph().variables();
  std::vector<int> merge_into(vars.size(), -1);
  bool held_gauge = false;  // the frame's gauge was one of its keyframes: its root's first, or a thinning's anchor
  for (const auto& k : it->second.track.keyframes()) {
    merge_into[static_cast<size_t>(k.variable)] = kDropVariable;
    held_gauge = held_gauge || vars[static_cast<size_t>(k.variable)].fixed;
  }
  for (const auto& [id, l] : it->second.landmarks) merge_into[static_cast<size_t>(l.variable)] = kDropVariable;
  // Then the gauge moves to the first keyframe of the frame's root (its new root when the body was it); a gauge on
  // another body's keyframe (slam_graph_thinning.cpp, choose_anchors) stays.
  const std::string root = frame == name ? next_root : frame;
  if (held_gauge && !root.empty() && !bodies_.at(root).track.empty())
    vars[static_cast<size_t>(bodies_.at(root).track.keyframes().front().variable)].fixed = true;
  drop_unseen_landmarks(kind, merge_into);
  Rebuilt fresh = rebuilt(kind, vars, merge_into);
  const auto involves = [&](const auto& x) {
    if constexpr (std::is_same_v<std::decay_t<decltype(x)>, SightingLink>)
      return x.observer == name || x.observed == name;
    else
      return x.from == name || x.to == name;
  };
  const auto purge = [&](auto& list) {
    const auto before = list.size();
    list.erase(std::remove_if(list.begin(), list.end(), involves), list.end());
    counters_.fleet_pending -= static_cast<int64_t>(before - list.size());
  };
  purge(pending_.sightings);
  purge(pending_.loops);
  counters_.loops_waiting -= static_cast<int64_t>(it->second.early_loops.size() + it->second.early_halves.size());
  for (auto& [other, b] : bodies_) {  // other bodies' loops from this one, waiting for their odometry
    std::erase_if(b.early_seen, [&](const auto& h) { return h.first == name; });
    const auto before = b.early_halves.size();
    std::erase_if(b.early_halves, [&](const auto& h) { return h.first == name; });
    counters_.loops_waiting -= static_cast<int64_t>(before - b.early_halves.size());
  }
  const auto waiting_before = waiting_wholes_.size();
  std::erase_if(waiting_wholes_, [&](const GraphContribution& c) {
    const auto* s = std::get_if<BodySighting>(&c.what);
    const auto* l = std::get_if<BodyLoop>(&c.what);
    const auto* j = std::get_if<FrameJoin>(&c.what);
    return c.body == name || (s && s->observer == name) || (l && l->from == name) || (j && j->keep == name);
  });
  counters_.fleet_contributions_waiting -= static_cast<int64_t>(waiting_before - waiting_wholes_.size());
  bodies_.erase(it);
  const bool others =
      std::any_of(bodies_.begin(), bodies_.end(), [&](const auto& x) { return x.second.planar == planar; });
  if (!others) {
    smoothers_[kind].reset();
    factor_tags_[kind].clear();
    gate_marginals_[kind].clear();
    return;
  }
  if (!fresh.smoother->update().ok) ++counters_.optimizer_failures;
  commit_rebuilt(kind, std::move(fresh));
}

}  // namespace sextant::slam
