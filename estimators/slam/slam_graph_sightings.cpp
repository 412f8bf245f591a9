// The SLAM layer's landmark sightings (slam_graph.hpp): waiting for the odometry, anchoring on the keyframe before
// them, gating against the current estimate and adding their range/bearing factors (sighting_model.hpp).
#include "estimators/slam/slam_graph.hpp"

#include "estimators/slam/sighting_model.hpp"

#include <algorithm>

namespace sextant::slam {

Eigen::MatrixXd SlamGraph::gate_marginal(const Body& b, int variable) {
  // A marginal is a forward solve along the variable's path to the root of the factor's elimination tree, which for
  // a landmark seen from everywhere is long: the sighting gate reuses one for kGateMarginalUpdates updates of the
  // smoother (deterministic: counted in updates, not time).  The marginal only shrinks as information arrives, so a
  // reused one makes the gate a little wider, never narrower.
  auto& cache = gate_marginals_[b.planar ? 1 : 0];
  auto it = cache.find(variable);
  if (it != cache.end() && counters_.updates - it->second.first < kGateMarginalUpdates) return it->second.second;
  Eigen::MatrixXd m = b.smoother->marginal_covariance(variable);
  if (m.size() > 0) cache[variable] = {counters_.updates, m};  // none yet (a pending variable, no factorization)
  return m;
}

void SlamGraph::add_sightings(const std::string& name, const SightingsInput& s, SlamListener& listener) {
  begin_local_input(name, s.utime);
  handle_sightings(name, s, listener);
  end_local_input(s.utime, listener);
}

Eigen::MatrixXd SlamGraph::keyframe_gate_marginal(const Body& b, size_t index) {
  // An update owed leaves the newest keyframes out of the factorization (no marginal yet); a few steps back is one
  // that is in, its marginal smaller than the newer keyframe's by the odometry between them only.
  for (size_t i = index + 1, steps = 0; i-- > 0 && steps < kGateMarginalSteps; ++steps) {
    Eigen::MatrixXd m = gate_marginal(b, b.track.keyframes()[i].variable);
    if (m.size() > 0) return m;
  }
  return {};
}

void SlamGraph::handle_sightings(const std::string& name, const SightingsInput& s, SlamListener& listener) {
  if (!options_.landmarks.enabled) return;
  const auto n = static_cast<int64_t>(s.sightings.size());
  auto it = bodies_.find(name);
  if (it == bodies_.end()) {
    counters_.sightings_unknown_source += n;
    return;
  }
  if (it->second.remote) {
    ++counters_.fleet_remote_inputs;
    return;
  }
  Body& b = it->second;
  if (s.planar != b.planar) {
    counters_.sightings_malformed += n;  // a planar body's sightings must be planar, and a 3-D body's 3-D
    return;
  }
  if (s.utime > b.track.last_utime()) {  // ahead of the odometry: anchored when the odometry passes it (add_odometry)
    if (options_.landmarks.max_waiting <= 0) {
      counters_.sightings_dropped += n;
      return;
    }
    if (b.early_sightings.size() >= static_cast<size_t>(options_.landmarks.max_waiting)) {
      counters_.sightings_dropped += static_cast<int64_t>(b.early_sightings.front().sightings.size());
      b.early_sightings.erase(b.early_sightings.begin());
    }
    const auto at = std::upper_bound(b.early_sightings.begin(), b.early_sightings.end(), s.utime,
                                     [](int64_t t, const SightingsInput& x) { return t < x.utime; });
    b.early_sightings.insert(at, s);
    return;
  }
  if (!b.track.keyframe_at_or_before(s.utime)) {
    counters_.sightings_before_keyframe += n;
    return;
  }
  const auto anchor = b.track.anchor_at(s.utime);
  if (!anchor) {
    counters_.sightings_unmatched += n;
    return;
  }
  add_anchored_sightings(name, b, s, *anchor, listener);
}

void SlamGraph::add_anchored_sightings(const std::string& name, Body& b, const SightingsInput& s,
                                       const TrackPoint& anchor, SlamListener& listener) {
  const size_t pending_before = pending_.sightings.size();
  SightingsInput accepted{s.utime, s.planar, s.sensor_in_body, {}};
  bool added = add_landmark_sightings(b, s, anchor, &accepted, listener);
  if (!accepted.sightings.empty()) listener.contributed({name, SightingsContribution{anchor_of(b, anchor), accepted}});
  for (const LandmarkSighting& ob : s.sightings) {
    const auto marker = options_.fleet.markers.find(ob.id);
    if (ob.id < 0 || !options_.fleet.enabled || marker == options_.fleet.markers.end()) continue;
    if (marker->second == name) {
      ++counters_.fleet_self_sightings;
      continue;
    }
    const BodySightingHalf half{marker->second, s.utime, s.sensor_in_body, ob, anchor_of(b, anchor)};
    listener.contributed({name, half});
    added = complete_body_sighting(name, half, listener) || added;
  }
  if (added) update_frame(b.frame, listener);
  // Shared landmarks and robot sightings are what place this body's frame among the others'.
  if (options_.fleet.enabled && (added || pending_.sightings.size() != pending_before)) try_joins(b.frame, listener);
}

bool SlamGraph::add_landmark_sightings(Body& b, const SightingsInput& s, const TrackPoint& anchor,
                                       SightingsInput* accepted, SlamListener& listener) {
  auto& landmarks = root_of(b).landmarks;  // the map of the body's frame
  // A landmark first seen since the last update has no marginal yet: the owed update runs now rather than the
  // sighting pass ungated (the solve period holds an update back at most once per new landmark).
  const auto unsolved = [&](const LandmarkSighting& ob) {
    const auto lm = landmarks.find(ob.id);
    return lm != landmarks.end() && gate_marginal(b, lm->second.variable).size() == 0;
  };
  if (accepted != nullptr && owes() && std::any_of(s.sightings.begin(), s.sightings.end(), unsolved))
    solve_owed(listener);
  const TrackKeyframe& kf = b.track.keyframes()[anchor.keyframe];
  const SightingModel model(b.planar, estimate(b, kf.variable), anchor, s.sensor_in_body);
  const int kind = b.planar ? 1 : 0;
  bool added = false;
  Eigen::VectorXd z;
  Eigen::MatrixXd R;
  for (const LandmarkSighting& ob : s.sightings) {
    if (ob.id < 0) {
      ++counters_.sightings_without_id;
      continue;
    }
    if (options_.fleet.enabled && options_.fleet.markers.contains(ob.id)) continue;  // a body: add_anchored_sightings
    if (!model.measurement(ob, z, R)) {
      ++counters_.sightings_malformed;
      continue;
    }
    auto lm = landmarks.find(ob.id);
    const bool known = lm != landmarks.end();
    const Eigen::Vector3d position =
        known ? b.smoother->graph().variables()[static_cast<size_t>(lm->second.variable)].point
              : model.landmark_from(ob);
    const SightingModel::Evaluation ev = model.evaluate(z, position);
    // The owner gates against its estimate; a remote body's sightings (accepted == nullptr) passed its owner's gate.
    if (known && accepted != nullptr) {
      const Eigen::MatrixXd p_landmark = gate_marginal(b, lm->second.variable);
      if (p_landmark.size() > 0) {  // determined: gate against the estimate
        const double d2 = model.mahalanobis(ev, R, options_.landmarks.gate_odometry_scale, p_landmark,
                                            keyframe_gate_marginal(b, anchor.keyframe));
        if (!(d2 <= sighting_gate_[kind])) {
          ++counters_.sightings_rejected;
          continue;
        }
      }
    }
    const Eigen::MatrixXd information = model.information(ev, R);
    try {
      if (!known) {
        graph::Variable v;
        v.kind = b.planar ? graph::VariableKind::kPoint2 : graph::VariableKind::kPoint3;
        v.point = position;
        v.id = next_variable_id_++;
        lm = landmarks.emplace(ob.id, Landmark{b.smoother->add_variable(v), 0}).first;
        ++counters_.landmarks;
      }
      add_factor(b,
                 std::make_unique<graph::PointObservationFactor>(kf.variable, lm->second.variable, model.model(), z,
                                                                 information, model.sensor_in_keyframe()),
                 FactorRole::kSighting, options_.landmarks.robust, sighting_width_[kind]);
    } catch (const std::invalid_argument&) {
      ++counters_.sightings_malformed;  // a value the checks above let through but the smoother refuses
      continue;
    }
    ++lm->second.sightings;
    ++counters_.sightings_accepted;
    if (accepted != nullptr) accepted->sightings.push_back(ob);
    added = true;
  }
  return added;
}

}  // namespace sextant::slam
