// The graph stage's landmark sightings (graph_stage.hpp): anchoring a sighting on the keyframe before it, gating it
// against the current estimate, and adding its range/bearing factor.
#include "daemon/engine/graph_stage.hpp"
#include "daemon/engine/planar_axes.hpp"
#include "daemon/engine/pose_conversion.hpp"

#include <Eigen/Cholesky>

#include <algorithm>

namespace sextant::engine {

Eigen::MatrixXd GraphStage::gate_marginal(const Body& b, int variable) {
  // A marginal is a forward solve along the variable's path to the root of the factor's elimination tree, which for
  // a landmark seen from everywhere is long: the sighting gate reuses one for kGateMarginalUpdates updates of the
  // smoother (deterministic: counted in updates, not time).  The marginal only shrinks as information arrives, so a
  // reused one makes the gate a little wider, never narrower.
  auto& cache = gate_marginals_[b.planar ? 1 : 0];
  auto it = cache.find(variable);
  if (it != cache.end() && updates_ - it->second.first < kGateMarginalUpdates) return it->second.second;
  Eigen::MatrixXd m = b.smoother->marginal_covariance(variable);
  cache[variable] = {updates_, m};
  return m;
}

void GraphStage::on_sightings(const LandmarkSightings& s, const Emit& emit) {
  const auto n = static_cast<int64_t>(s.observations.size());
  auto it = bodies_.find(s.source);
  if (it == bodies_.end()) {
    sightings_unknown_source_ += n;
    return;
  }
  Body& b = it->second;
  if (s.planar != b.planar) {
    sightings_malformed_ += n;  // a planar body's sightings must be planar, and a 3-D body's 3-D
    return;
  }
  if (s.utime > b.last_utime) {  // ahead of the odometry: anchored when the odometry passes it (on_odometry)
    if (config_.landmarks.max_waiting <= 0) {
      sightings_dropped_ += n;
      return;
    }
    if (b.early_sightings.size() >= static_cast<size_t>(config_.landmarks.max_waiting)) {
      sightings_dropped_ += static_cast<int64_t>(b.early_sightings.front().observations.size());
      b.early_sightings.erase(b.early_sightings.begin());
    }
    const auto at = std::upper_bound(b.early_sightings.begin(), b.early_sightings.end(), s.utime,
                                     [](int64_t t, const LandmarkSightings& x) { return t < x.utime; });
    b.early_sightings.insert(at, s);
    return;
  }
  if (b.keyframes.empty() || b.by_utime.upper_bound(s.utime) == b.by_utime.begin()) {
    sightings_before_keyframe_ += n;
    return;
  }
  const auto anchor = anchor_of(b, s.utime);
  if (!anchor) {
    sightings_unmatched_ += n;
    return;
  }
  add_sightings(s, b, *anchor, emit);
}

std::optional<GraphStage::SightingAnchor> GraphStage::anchor_of(const Body& b, int64_t utime) const {
  const size_t k = std::prev(b.by_utime.upper_bound(utime))->second;
  SE3 pose = b.last_odom;
  if (utime != b.last_utime) {
    auto at = std::lower_bound(b.odometry.begin(), b.odometry.end(), utime,
                               [](const std::pair<int64_t, SE3>& x, int64_t t) { return x.first < t; });
    if (at == b.odometry.end() || (at->first != utime && at == b.odometry.begin())) return std::nullopt;
    if (at->first == utime) {
      pose = at->second;
    } else {
      const auto& [t0, p0] = *std::prev(at);
      const double a = static_cast<double>(utime - t0) / static_cast<double>(at->first - t0);
      pose = p0 * SE3::exp(a * p0.between(at->second).log());
    }
  }
  // The odometry's covariance from the keyframe to the next keyframe (or to the latest odometry): it contains the
  // motion to the sighting and a little more.
  const Matrix6 cov = k + 1 < b.keyframes.size() ? b.keyframes[k + 1].edge_covariance : b.since_keyframe;
  return SightingAnchor{k, b.keyframes[k].odom.between(pose), cov};
}

void GraphStage::add_sightings(const LandmarkSightings& s, Body& b, const SightingAnchor& anchor, const Emit& emit) {
  using graph::PointObservationFactor;
  const KeyframeNode& kf = b.keyframes[anchor.keyframe];
  const int n = b.planar ? 2 : 3;
  const auto model = b.planar ? PointObservationFactor::Model::kRangeBearing : PointObservationFactor::Model::kRangeAzimuthElevation;
  const SE3 sensor_in_body = to_se3(s.sensor_in_body);
  const SE3 sensor = anchor.motion * sensor_in_body;  // the sensor at the sighting, in the keyframe's frame
  // The pose at the sighting X_K D and the landmark, as a two-variable problem to evaluate the factor on: its first
  // Jacobian is dh/dD (a right perturbation of X_K D is one of D).
  std::vector<graph::Variable> local(2);
  local[0].kind = b.planar ? graph::VariableKind::kPose2 : graph::VariableKind::kPose3;
  local[1].kind = b.planar ? graph::VariableKind::kPoint2 : graph::VariableKind::kPoint3;
  const SE3 at_sighting = b.smoother->graph().variables()[static_cast<size_t>(kf.variable)].as_se3() * anchor.motion;
  if (b.planar) local[0].pose2 = SE2::from_se3(at_sighting);
  else local[0].pose3 = at_sighting;
  const Eigen::MatrixXd sigma_d = b.planar ? Eigen::MatrixXd(planar_block(anchor.covariance)) : Eigen::MatrixXd(anchor.covariance);
  const Matrix6 ad6 = anchor.motion.inverse().adjoint();  // X_K Exp(xi) D = X_K D Exp(Ad(D^-1) xi)
  const Eigen::MatrixXd ad = b.planar ? Eigen::MatrixXd(planar_block(ad6)) : Eigen::MatrixXd(ad6);
  const double k2 = config_.landmarks.gate_odometry_scale * config_.landmarks.gate_odometry_scale;
  bool added = false;
  for (const LandmarkObservation& ob : s.observations) {
    if (ob.id < 0) {
      ++sightings_without_id_;
      continue;
    }
    Eigen::VectorXd z(n);
    z[0] = ob.range, z[1] = ob.azimuth;
    if (!b.planar) z[2] = ob.elevation;
    const Eigen::MatrixXd R = ob.covariance.topLeftCorner(n, n);
    if (!z.allFinite() || !(ob.range > 0) || !R.allFinite() || R.llt().info() != Eigen::Success) {
      ++sightings_malformed_;
      continue;
    }
    auto lm = b.landmarks.find(ob.id);
    const bool known = lm != b.landmarks.end();
    if (known) {
      local[1].point = b.smoother->graph().variables()[static_cast<size_t>(lm->second.variable)].point;
    } else {  // the landmark where this sighting puts it: X_K D S l(z)
      const double c = std::cos(b.planar ? 0.0 : ob.elevation);
      const Eigen::Vector3d l(ob.range * c * std::cos(ob.azimuth), ob.range * c * std::sin(ob.azimuth),
                              b.planar ? 0.0 : ob.range * std::sin(ob.elevation));
      local[1].point = at_sighting * sensor_in_body * l;
      if (b.planar) local[1].point.z() = 0;
    }
    const PointObservationFactor probe(0, 1, model, z, Eigen::MatrixXd::Identity(n, n), sensor_in_body);
    graph::Linearization lin = probe.make_linearization(local);
    probe.linearize(local, lin);
    const Eigen::MatrixXd odometry_part = lin.jacobians[0] * sigma_d * lin.jacobians[0].transpose();
    if (known) {
      const Eigen::MatrixXd p_landmark = gate_marginal(b, lm->second.variable);
      if (p_landmark.size() > 0) {  // determined: gate against the estimate
        Eigen::MatrixXd S = R + k2 * odometry_part + lin.jacobians[1] * p_landmark * lin.jacobians[1].transpose();
        const Eigen::MatrixXd p_keyframe = gate_marginal(b, kf.variable);
        if (p_keyframe.size() > 0) {
          const Eigen::MatrixXd jk = lin.jacobians[0] * ad;
          S += jk * p_keyframe * jk.transpose();
        }
        const double d2 = lin.error.dot(S.ldlt().solve(lin.error));
        if (!(d2 <= (b.planar ? sighting_gate_planar_ : sighting_gate_spatial_))) {
          ++sightings_rejected_;
          continue;
        }
      }
    }
    Eigen::MatrixXd cov = R + odometry_part;
    cov = 0.5 * (cov + cov.transpose());
    Eigen::MatrixXd information = cov.llt().solve(Eigen::MatrixXd::Identity(n, n));
    information = 0.5 * (information + information.transpose());
    try {
      if (!known) {
        graph::Variable v = local[1];
        v.id = next_variable_id_++;
        lm = b.landmarks.emplace(ob.id, Body::Landmark{b.smoother->add_variable(v), 0}).first;
        ++landmarks_;
      }
      add_factor(b, std::make_unique<PointObservationFactor>(kf.variable, lm->second.variable, model, z, information, sensor),
                 FactorRole::kSighting, config_.landmarks.robust, b.planar ? sighting_width_planar_ : sighting_width_spatial_);
    } catch (const std::invalid_argument&) {
      ++sightings_malformed_;  // a value the checks above let through but the smoother refuses
      continue;
    }
    ++lm->second.sightings;
    ++sightings_accepted_;
    added = true;
  }
  if (added) optimize_and_publish(s.source, b, b.keyframes.back().utime, emit);
}

}  // namespace sextant::engine
