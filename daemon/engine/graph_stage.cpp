#include "daemon/engine/graph_stage.hpp"

#include "assoc/chi_square.hpp"
#include "daemon/engine/planar_axes.hpp"
#include "daemon/engine/pose_conversion.hpp"
#include "daemon/engine/pose_covariance.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace sextant::engine {
namespace {

/// The information of a 3-D RelativePoseFactor from an information over sextant's tangent [t; phi] (the odometry's
/// and the loops' covariances, rotation in radians).  The factor's residual is g2o's [t_E; vec(q_E)] with
/// vec(q_E) ~ phi / 2, so [t; phi] ~ T [t_E; vec(q_E)], T = diag(I, 2 I), and its information is T Omega T: the
/// rotation block times 4, the cross blocks times 2 (the inverse of replay::g2o_information_to_sextant).  Passing
/// Omega unchanged weighted every rotation 4 times too little.
Matrix6d residual_information(const Eigen::MatrixXd& tangent) {
  Matrix6d out = tangent;
  out.bottomRows<3>() *= 2;
  out.rightCols<3>() *= 2;
  return out;
}

graph::IncrementalOptions smoother_options(const GraphConfig& c, bool planar) {
  graph::IncrementalOptions o = c.smoother;
  o.kernel = c.robust;
  o.kernel_width = kernel_width_for(c, planar);
  return o;
}

/// The covariance added to the odometry edge of a keyframe re-anchored after a jump (KeyframeSelector's kReanchored):
/// the odometry across the jump is what made it implausible, so the edge only says "somewhere around there": each
/// translation axis gets the variance |rho|^2 and each rotation axis |phi|^2, mu = Log(edge) = [rho; phi] (planar:
/// x, y and yaw only).  The new segment stays connected (one graph, one map frame, the smoother's system stays
/// determined) and starts where the odometry put it, but a loop across the jump moves it almost freely, and the loop
/// gate's odometry path covariance (on_loop) widens by the same amount, so such loops are not refused.
Matrix6 jump_covariance(const SE3& edge, bool planar) {
  Matrix6 c = Matrix6::Zero();
  if (planar) {
    const Eigen::Vector3d mu = SE2::from_se3(edge).log();
    c(0, 0) = c(1, 1) = mu.head<2>().squaredNorm();
    c(5, 5) = mu[2] * mu[2];
  } else {
    const Vector6d mu = edge.log();
    c.topLeftCorner<3, 3>().diagonal().setConstant(mu.head<3>().squaredNorm());
    c.bottomRightCorner<3, 3>().diagonal().setConstant(mu.tail<3>().squaredNorm());
  }
  return c;
}

/// The configured kernel width, or the one "auto" gives a residual of `dimension` gated at `probability`.
double auto_kernel_width(const GraphConfig& config, int dimension, double probability) {
  if (config.kernel_width) return *config.kernel_width;
  const double q = assoc::chi2_quantile(dimension, probability);
  return config.robust == graph::RobustKernel::kDcs ? q : std::sqrt(q);
}

}  // namespace

double kernel_width_for(const GraphConfig& config, bool planar) {
  return auto_kernel_width(config, planar ? 3 : 6, config.loop_gate_probability);
}

double sighting_kernel_width_for(const GraphConfig& config, bool planar) {
  return auto_kernel_width(config, planar ? 2 : 3, config.landmarks.gate_probability);
}

GraphStage::GraphStage(const GraphConfig& config, std::shared_ptr<GraphCorrectionBoard> corrections)
    : config_(config),
      corrections_(std::move(corrections)),
      proposer_(config.proposals),
      chi2_gate_planar_(assoc::chi2_quantile(3, config.loop_gate_probability)),
      chi2_gate_spatial_(assoc::chi2_quantile(6, config.loop_gate_probability)),
      sighting_gate_planar_(assoc::chi2_quantile(2, config.landmarks.gate_probability)),
      sighting_gate_spatial_(assoc::chi2_quantile(3, config.landmarks.gate_probability)),
      sighting_width_planar_(sighting_kernel_width_for(config, true)),
      sighting_width_spatial_(sighting_kernel_width_for(config, false)) {
  KeyframeSelector check(config.keyframes);  // throws std::invalid_argument for bad thresholds
  (void)check;
}

graph::IncrementalSmoother& GraphStage::smoother_for(bool planar) {
  auto& s = smoothers_[planar ? 1 : 0];
  if (!s) s = std::make_unique<graph::IncrementalSmoother>(smoother_options(config_, planar));
  return *s;
}

std::unique_ptr<graph::Factor> GraphStage::odometry_factor(bool planar, int from, int to, const SE3& edge, const Matrix6& covariance) {
  const Eigen::MatrixXd cov = planar ? Eigen::MatrixXd(planar_block(covariance)) : Eigen::MatrixXd(covariance);
  Eigen::LLT<Eigen::MatrixXd> llt(cov);
  if (llt.info() != Eigen::Success || !cov.allFinite()) return nullptr;
  Eigen::MatrixXd information = llt.solve(Eigen::MatrixXd::Identity(cov.rows(), cov.cols()));
  information = 0.5 * (information + information.transpose());
  if (planar) return std::make_unique<graph::RelativePoseFactor>(from, to, SE2::from_se3(edge), Eigen::Matrix3d(information));
  return std::make_unique<graph::RelativePoseFactor>(from, to, edge, residual_information(information));
}

void GraphStage::add_factor(Body& b, std::unique_ptr<graph::Factor> factor, FactorRole role, bool robust,
                            std::optional<double> width) {
  b.smoother->add_factor(std::move(factor), robust, width);
  factor_tags_[b.planar ? 1 : 0].push_back({role, robust, width});
}

void GraphStage::handle(const Event& e, const Emit& emit) {
  if (const auto* o = std::get_if<Odometry>(&e)) on_odometry(*o, emit);
  else if (const auto* l = std::get_if<LoopClosure>(&e)) on_loop(*l, emit);
  else if (const auto* s = std::get_if<LandmarkSightings>(&e); s && config_.landmarks.enabled) on_sightings(*s, emit);
}

void GraphStage::on_odometry(const Odometry& o, const Emit& emit) {
  auto it = bodies_.find(o.source);
  if (it == bodies_.end()) {
    KeyframeSelectorOptions ko = config_.keyframes;
    ko.planar = o.planar;
    Body body;
    body.planar = o.planar;
    body.selector = KeyframeSelector(ko);
    body.smoother = &smoother_for(o.planar);
    body.feed = TrajectoryFeed(config_.trajectory);
    it = bodies_.emplace(o.source, std::move(body)).first;
  } else if (o.utime <= it->second.last_utime) {
    ++out_of_order_;
    return;
  }
  Body& b = it->second;
  const SE3 odom = to_se3(o.pose);
  // Sightings that waited for this message (taken after the previous one): anchored on the newest keyframe, their
  // part of the increment interpolated on the group, Delta_a = Exp(a Log Delta) with covariance a Q.
  std::vector<std::pair<LandmarkSightings, SightingAnchor>> due_sightings;
  if (!b.keyframes.empty()) {
    const SE3 delta = b.last_odom.between(odom);
    const Matrix6 q = increment_covariance(o, delta, b.last_odom_covariance, config_.min_increment_variance);
    const SE3 keyframe_to_last = b.keyframes.back().odom.between(b.last_odom);
    while (!b.early_sightings.empty() && b.early_sightings.front().utime <= o.utime) {
      const double a = static_cast<double>(b.early_sightings.front().utime - b.last_utime) / static_cast<double>(o.utime - b.last_utime);
      const SE3 part = SE3::exp(a * delta.log());
      SightingAnchor anchor{b.keyframes.size() - 1, keyframe_to_last * part, compose_covariance(b.since_keyframe, part, a * q)};
      due_sightings.emplace_back(std::move(b.early_sightings.front()), anchor);
      b.early_sightings.erase(b.early_sightings.begin());
    }
    b.since_keyframe = compose_covariance(b.since_keyframe, delta, q);
  }
  while (!b.early_sightings.empty() && b.early_sightings.front().utime <= o.utime) {  // a body without keyframes
    sightings_before_keyframe_ += static_cast<int64_t>(b.early_sightings.front().observations.size());
    b.early_sightings.erase(b.early_sightings.begin());
  }
  b.last_utime = o.utime;
  b.last_odom = odom;
  remember_odometry(b, o.utime, odom, static_cast<size_t>(config_.odometry_history));
  b.last_odom_covariance = o.covariance;

  for (const auto& [sightings, anchor] : due_sightings) add_sightings(sightings, b, anchor, emit);
  on_keyframe_candidate(o, b, odom, emit);
  // Loops that arrived before the odometry of their times: try them now that the odometry has reached them.
  if (!b.early_loops.empty()) {
    std::vector<LoopClosure> due, later;
    for (auto& l : b.early_loops) (std::max(l.utime_from, l.utime_to) <= b.last_utime ? due : later).push_back(std::move(l));
    b.early_loops = std::move(later);
    for (const auto& l : due) on_loop(l, emit);
  }
}

void GraphStage::remember_odometry(Body& b, int64_t utime, const SE3& pose, size_t history) {
  if (b.odometry.size() >= history)
    b.odometry.erase(b.odometry.begin(), b.odometry.begin() + static_cast<std::ptrdiff_t>(b.odometry.size() / 2));
  b.odometry.emplace_back(utime, pose);
}

void GraphStage::on_keyframe_candidate(const Odometry& o, Body& b, const SE3& odom, const Emit& emit) {
  const KeyframeDecision d = b.selector.decide(odom);
  if (d == KeyframeDecision::kImplausible) ++keyframes_rejected_;
  if (d != KeyframeDecision::kKeyframe && d != KeyframeDecision::kReanchored) return;
  const bool reanchored = d == KeyframeDecision::kReanchored && !b.keyframes.empty();

  KeyframeNode node;
  node.utime = o.utime;
  node.odom = odom;
  node.odom_covariance = o.covariance;
  std::unique_ptr<graph::Factor> edge_factor;
  if (!b.keyframes.empty()) {
    node.edge = b.keyframes.back().odom.between(odom);
    node.edge_covariance = b.since_keyframe;
    if (reanchored) node.edge_covariance += jump_covariance(node.edge, b.planar);
    // A covariance that cannot be inverted drops the keyframe (the selector goes back to the last keyframe in the
    // graph) and keeps accumulating towards the next one, whose edge spans the dropped pose.
    edge_factor = odometry_factor(b.planar, b.keyframes.back().variable, -1, node.edge, node.edge_covariance);
    if (!edge_factor) {
      drop_keyframe(b);
      return;
    }
  }
  graph::Variable v;
  v.id = next_variable_id_++;
  v.kind = b.planar ? graph::VariableKind::kPose2 : graph::VariableKind::kPose3;
  SE3 initial = odom;
  if (b.keyframes.empty()) {
    v.fixed = true;  // the body's map frame: its odometry frame at the first keyframe
  } else {
    initial = b.smoother->graph().variables()[static_cast<size_t>(b.keyframes.back().variable)].as_se3() * node.edge;
  }
  if (b.planar) v.pose2 = SE2::from_se3(initial);
  else v.pose3 = initial;
  try {
    node.variable = b.smoother->add_variable(v);
    if (edge_factor)
      add_factor(b, edge_factor->rebind({b.keyframes.back().variable, node.variable}), FactorRole::kOdometry, false, std::nullopt);
  } catch (const std::invalid_argument&) {
    drop_keyframe(b);  // a non-finite pose or information: never reaches the smoother's system
    return;
  }
  node.id = b.next_keyframe_id++;
  b.since_keyframe.setZero();
  b.by_utime[o.utime] = b.keyframes.size();
  b.keyframes.push_back(node);
  ++keyframes_;
  if (reanchored) ++keyframes_reanchored_;
  optimize_and_publish(o.source, b, o.utime, emit);

  if (config_.propose_loops) {
    // Candidates among the keyframes in the graph (positions in b.keyframes; with lifelong thinning the places kept
    // of the older map), named by their keyframe ids.
    const int64_t k = static_cast<int64_t>(b.keyframes.size()) - 1;
    for (const LoopProposal& p : proposer_.propose(k)) {
      MatchRequest r;
      r.utime = o.utime;
      r.source = o.source;
      r.request_id = next_request_id_++;
      r.kind = p.random ? "random" : "local";
      const KeyframeNode& a = b.keyframes[static_cast<size_t>(p.from)];
      const KeyframeNode& c = b.keyframes[static_cast<size_t>(p.to)];
      r.a = Keyframe{a.id, a.utime, to_pose(b.smoother->graph().variables()[static_cast<size_t>(a.variable)].as_se3())};
      r.b = Keyframe{c.id, c.utime, to_pose(b.smoother->graph().variables()[static_cast<size_t>(c.variable)].as_se3())};
      ++requests_;
      emit(r);
    }
  }
  maybe_thin(b.planar);
}

std::optional<GraphStage::LoopEnd> GraphStage::resolve(const Body& b, int64_t keyframe_id, int64_t utime) const {
  // By id: a keyframe of the graph at exactly that time.
  const auto by_id = std::lower_bound(b.keyframes.begin(), b.keyframes.end(), keyframe_id,
                                      [](const KeyframeNode& k, int64_t id) { return k.id < id; });
  if (keyframe_id >= 0 && by_id != b.keyframes.end() && by_id->id == keyframe_id && by_id->utime == utime)
    return LoopEnd{static_cast<size_t>(by_id - b.keyframes.begin()), SE3(), Matrix6::Zero()};
  // The odometry pose at the loop's time (exact stamp, as a front end answers about frames it was given).
  std::optional<SE3> at_time;
  auto at = std::lower_bound(b.odometry.begin(), b.odometry.end(), utime,
                             [](const std::pair<int64_t, SE3>& x, int64_t t) { return x.first < t; });
  if (at != b.odometry.end() && at->first == utime) at_time = at->second;
  const auto thinned = std::lower_bound(b.thinned.begin(), b.thinned.end(), utime,
                                        [](const ThinnedKeyframe& k, int64_t t) { return k.utime < t; });
  if (!at_time && thinned != b.thinned.end() && thinned->utime == utime) at_time = thinned->odom;
  // The nearest keyframe of the graph in time, within the tolerance: the odometry bridges the gap.
  const auto tolerance = static_cast<int64_t>(config_.loop_time_tolerance_s * 1e6);
  auto hi = b.by_utime.lower_bound(utime);
  std::optional<size_t> best;
  int64_t best_gap = tolerance + 1;
  if (hi != b.by_utime.end() && hi->first - utime < best_gap) best = hi->second, best_gap = hi->first - utime;
  if (hi != b.by_utime.begin()) {
    auto lo = std::prev(hi);
    if (utime - lo->first < best_gap) best = lo->second;
  }
  if (best) {
    const KeyframeNode& kf = b.keyframes[*best];
    if (kf.utime == utime) return LoopEnd{*best, SE3(), Matrix6::Zero()};
    if (!at_time) return std::nullopt;
    return LoopEnd{*best, kf.odom.between(*at_time), Matrix6::Zero()};
  }
  // A time whose keyframes were thinned (lifelong): the keyframe of the graph before it on the odometry chain, the
  // odometry from there, and as that motion's covariance the covariance of the whole (composed) edge from that
  // keyframe to the next one of the graph, which contains it: an upper bound, so the loop is weakened, not bent.
  if (!at_time || b.by_utime.empty() || utime < b.by_utime.begin()->first || utime > b.keyframes.back().utime) return std::nullopt;
  const size_t k = std::prev(b.by_utime.upper_bound(utime))->second;
  if (k + 1 >= b.keyframes.size()) return std::nullopt;
  return LoopEnd{k, b.keyframes[k].odom.between(*at_time), b.keyframes[k + 1].edge_covariance};
}

void GraphStage::drop_keyframe(Body& b) {
  ++bad_edges_;
  b.selector.reset_reference(b.keyframes.empty() ? std::nullopt : std::optional<SE3>(b.keyframes.back().odom));
}

void GraphStage::on_loop(const LoopClosure& l, const Emit& emit) {
  auto it = bodies_.find(l.source);
  if (it == bodies_.end()) {
    ++loops_unknown_source_;
    return;
  }
  Body& b = it->second;
  const auto end_from = resolve(b, l.keyframe_from, l.utime_from);
  const auto end_to = resolve(b, l.keyframe_to, l.utime_to);
  if ((!end_from || !end_to) && std::max(l.utime_from, l.utime_to) > b.last_utime && b.early_loops.size() < 256) {
    b.early_loops.push_back(l);  // ahead of the odometry: retried when it gets there
    return;
  }
  if (!end_from || !end_to || end_from->keyframe == end_to->keyframe) {
    ++loops_unmatched_;
    return;
  }
  const std::optional<size_t> from = end_from->keyframe, to = end_to->keyframe;
  // The loop's information, with the uncertainty of the odometry that moved an end from a thinned keyframe onto one
  // of the graph added to the loop's covariance (in the loop's frame; zero for ends on keyframes of the graph).
  Matrix6 information = l.information;
  if (!end_from->covariance.isZero() || !end_to->covariance.isZero()) {
    ++loops_on_thinned_;
    const Eigen::MatrixXd cov = (b.planar ? Eigen::MatrixXd(planar_block(l.information)) : Eigen::MatrixXd(l.information)).inverse();
    const Matrix6 extra = end_from->covariance + end_to->covariance;
    const Eigen::MatrixXd widened = cov + (b.planar ? Eigen::MatrixXd(planar_block(extra)) : Eigen::MatrixXd(extra));
    const Eigen::MatrixXd info = widened.inverse();
    information = b.planar ? embed_planar(info) : Matrix6(0.5 * (info + info.transpose()));
  }
  // Consistency: the loop against the current estimate, with the loop's covariance plus the odometry's between the
  // two keyframes (an upper bound of the estimate's relative uncertainty, so a true loop passes with the gate's
  // probability however far the odometry drifted — as long as the odometry's covariance is honest; it is scaled up
  // by loop_gate_odometry_scale for the biases real odometry does not report).
  const size_t lo = std::min(*from, *to), hi = std::max(*from, *to);
  Matrix6 path = Matrix6::Zero();
  SE3 chain;
  for (size_t k = lo + 1; k <= hi; ++k) {
    path = compose_covariance(path, b.keyframes[k].edge, b.keyframes[k].edge_covariance);
    chain = chain * b.keyframes[k].edge;
  }
  if (*from > *to) {  // the covariance of the inverse motion: Ad(X) P Ad(X)'
    const Matrix6 ad = chain.adjoint();
    path = ad * path * ad.transpose();
  }
  const auto& vars = b.smoother->graph().variables();
  const SE3 predicted = vars[static_cast<size_t>(b.keyframes[*from].variable)].as_se3().between(
      vars[static_cast<size_t>(b.keyframes[*to].variable)].as_se3());
  // The loop moved onto the keyframes: T_kf_from^-1 T_kf_to = D_from z D_to^-1.
  const SE3 z = end_from->motion * to_se3(l.relative) * end_to->motion.inverse();
  double d2;
  if (b.planar) {
    const Eigen::Matrix3d info = planar_block(information);
    const Eigen::Vector3d e = SE2::from_se3(z).between(SE2::from_se3(predicted)).log();
    const double k2 = config_.loop_gate_odometry_scale * config_.loop_gate_odometry_scale;
    const Eigen::Matrix3d S = info.inverse() + k2 * planar_block(path);
    d2 = e.dot(S.ldlt().solve(e));
  } else {
    const Vector6d e = z.between(predicted).log();
    const Matrix6 S = information.inverse() + config_.loop_gate_odometry_scale * config_.loop_gate_odometry_scale * path;
    d2 = e.dot(S.ldlt().solve(e));
  }
  if (!(d2 <= (b.planar ? chi2_gate_planar_ : chi2_gate_spatial_))) {
    ++loops_rejected_;
    return;
  }
  const int vf = b.keyframes[*from].variable, vt = b.keyframes[*to].variable;
  try {
    if (b.planar)
      add_factor(b, std::make_unique<graph::RelativePoseFactor>(vf, vt, SE2::from_se3(z), Eigen::Matrix3d(planar_block(information))),
                 FactorRole::kLoop, true, std::nullopt);
    else
      add_factor(b, std::make_unique<graph::RelativePoseFactor>(vf, vt, z, residual_information(information)), FactorRole::kLoop, true,
                 std::nullopt);
  } catch (const std::invalid_argument&) {
    ++loops_rejected_;  // an information the intake let through but the smoother cannot use (e.g. planar block)
    return;
  }
  ++loops_accepted_;
  optimize_and_publish(l.source, b, b.keyframes.back().utime, emit);
}

void GraphStage::optimize_and_publish(const std::string& source, Body& b, int64_t utime, const Emit& emit) {
  const auto t0 = std::chrono::steady_clock::now();
  const graph::IncrementalStatus st = b.smoother->update();
  last_update_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  ++updates_;
  rebuilds_ += st.rebuilt ? 1 : 0;
  relinearized_ += st.relinearized_factors;
  if (!st.ok) {
    ++optimizer_failures_;
    return;
  }
  b.newest_utime = utime;
  if (b.feed.due(utime)) publish_trajectory(source, b, utime, st.solves, false, emit);

  const KeyframeNode& newest = b.keyframes.back();
  GraphCorrection c;
  c.keyframe_utime = newest.utime;
  c.keyframe_odom = newest.odom;
  c.keyframe_map = b.smoother->graph().variables()[static_cast<size_t>(newest.variable)].as_se3();
  const Eigen::MatrixXd marginal = b.smoother->marginal_covariance(newest.variable);
  if (marginal.size() > 0) c.keyframe_covariance = b.planar ? embed_planar(marginal) : Matrix6(marginal);
  c.keyframe_odom_covariance = newest.odom_covariance;
  corrections_->set(source, c);
}

void GraphStage::publish_trajectory(const std::string& source, Body& b, int64_t utime, int solves, bool flush,
                                    const Emit& emit) {
  Trajectory header;
  header.source = source;
  header.chi2 = b.smoother->chi2();
  header.iterations = solves;
  header.solve_ms = last_update_ms_;
  for (auto& t : b.feed.publish(utime, keyframes(source), header, flush)) {
    trajectory_bytes_ += static_cast<int64_t>(t.keyframes.size()) * 72 + static_cast<int64_t>(t.removed_ids.size()) * 8;
    ++trajectory_messages_;
    emit(std::move(t));
  }
}

void GraphStage::finish(const Emit& emit) {
  for (auto& [source, b] : bodies_)
    if (!b.keyframes.empty()) publish_trajectory(source, b, b.newest_utime, 0, true, emit);
}

std::vector<Keyframe> GraphStage::keyframes(const std::string& source) const {
  std::vector<Keyframe> out;
  auto it = bodies_.find(source);
  if (it == bodies_.end()) return out;
  const auto& vars = it->second.smoother->graph().variables();
  for (size_t k = 0; k < it->second.keyframes.size(); ++k) {
    const KeyframeNode& n = it->second.keyframes[k];
    out.push_back(Keyframe{n.id, n.utime, to_pose(vars[static_cast<size_t>(n.variable)].as_se3())});
  }
  return out;
}

std::vector<GraphLandmark> GraphStage::landmarks(const std::string& source) const {
  std::vector<GraphLandmark> out;
  auto it = bodies_.find(source);
  if (it == bodies_.end()) return out;
  for (const auto& [id, l] : it->second.landmarks)
    out.push_back(GraphLandmark{id, it->second.smoother->graph().variables()[static_cast<size_t>(l.variable)].point, l.sightings});
  return out;
}

Counters GraphStage::counters() const {
  return {{"updates", updates_},
          {"keyframes", keyframes_},
          {"keyframes_rejected", keyframes_rejected_},
          {"keyframes_reanchored", keyframes_reanchored_},
          {"match_requests", requests_},
          {"loops_accepted", loops_accepted_},
          {"loops_rejected", loops_rejected_},
          {"loops_unmatched", loops_unmatched_},
          {"loops_unknown_source", loops_unknown_source_},
          {"optimizer_failures", optimizer_failures_},
          {"rebuilds", rebuilds_},
          {"relinearized_factors", relinearized_},
          {"odometry_out_of_order", out_of_order_},
          {"odometry_edges_rejected", bad_edges_},
          {"landmarks", landmarks_},
          {"sightings_accepted", sightings_accepted_},
          {"sightings_rejected", sightings_rejected_},
          {"sightings_without_id", sightings_without_id_},
          {"sightings_unknown_source", sightings_unknown_source_},
          {"sightings_before_keyframe", sightings_before_keyframe_},
          {"sightings_unmatched", sightings_unmatched_},
          {"sightings_malformed", sightings_malformed_},
          {"sightings_dropped", sightings_dropped_},
          {"last_update_us", static_cast<int64_t>(last_update_ms_ * 1000)},
          {"trajectory_messages", trajectory_messages_},
          {"thinnings", thinnings_},
          {"thinning_failures", thinning_failures_},
          {"keyframes_thinned", keyframes_thinned_},
          {"loops_thinned", loops_thinned_},
          {"sightings_thinned", sightings_thinned_},
          {"landmarks_thinned", landmarks_thinned_},
          {"loops_on_thinned_keyframes", loops_on_thinned_},
          {"thinning_us_last", thinning_us_},
          {"thinning_us_max", thinning_us_max_},
          {"thinning_solve_us_last", thinning_solve_us_},
          {"graph_keyframes", graph_keyframes()},
          {"graph_landmarks", graph_landmarks()},
          {"graph_factors", graph_factors()},
          {"trajectory_keyframe_bytes", trajectory_bytes_}};
}

}  // namespace sextant::engine
