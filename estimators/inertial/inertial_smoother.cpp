#include "estimators/inertial/inertial_smoother.hpp"

#include "estimators/graph/factor_graph.hpp"
#include "estimators/graph/linear_prior_factor.hpp"
#include "estimators/graph/optimizer.hpp"
#include "estimators/lie/pose_covariance.hpp"
#include "estimators/slam/pose_factors.hpp"
#include "estimators/spd_matrix.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace sextant::inertial {
namespace {

// A keyframe's four variables, in this order, at graph index 4 * (its place in the window) + slot.
enum Slot { kPose = 0, kVelocity = 1, kGyroBias = 2, kAccelBias = 3, kSlots = 4 };

// A variable by keyframe sequence number and slot (stable while keyframes come and go).
struct VariableRef {
  int64_t keyframe;
  int slot;
};

struct StoredFactor {
  std::unique_ptr<graph::Factor> factor;
  std::vector<VariableRef> variables;
  bool gnss = false;
};

struct Keyframe {
  int64_t seq = 0;
  double t = 0;
  std::vector<graph::Variable> vars;  // kSlots of them
  std::optional<SE3> odometry;
  std::vector<StoredFactor> factors;  // those to the previous keyframe, and the fixes on this one
};

graph::Variable make_variable(int64_t id, graph::VariableKind kind) {
  graph::Variable v;
  v.id = id;
  v.kind = kind;
  return v;
}

std::vector<graph::Variable> keyframe_variables(int64_t seq, const NavState& x, const ImuBias& b) {
  std::vector<graph::Variable> v = {make_variable(seq * kSlots + kPose, graph::VariableKind::kPose3),
                                    make_variable(seq * kSlots + kVelocity, graph::VariableKind::kVector3),
                                    make_variable(seq * kSlots + kGyroBias, graph::VariableKind::kVector3),
                                    make_variable(seq * kSlots + kAccelBias, graph::VariableKind::kVector3)};
  v[kPose].pose3 = SE3(SO3(x.R), x.p);
  v[kVelocity].point = x.v;
  v[kGyroBias].point = b.gyro;
  v[kAccelBias].point = b.accel;
  return v;
}

constexpr KeyframeVariables kLocal{kPose, kVelocity, kGyroBias, kAccelBias};

// A factor linearized with some of its variables at fixed values: the first-estimates Jacobians of Huang, Mourikis
// and Roumeliotis ("Observability-based rules for designing consistent EKF SLAM estimators", IJRR 2010).  The
// variables of the marginalization prior enter every factor's Jacobians at the prior's linearization point, so the
// prior and the factors agree on the unobservable directions (global position, yaw about gravity) and the window
// does not gain information along them from relinearization alone.  The residual is the inner factor's at the
// current values.
class FirstEstimateJacobians final : public graph::Factor {
 public:
  FirstEstimateJacobians(std::unique_ptr<graph::Factor> inner, std::vector<std::pair<int, graph::Variable>> first)
      : graph::Factor(inner->variables(), inner->information()), inner_(std::move(inner)), first_(std::move(first)) {}
  FirstEstimateJacobians(const FirstEstimateJacobians& o)
      : graph::Factor(o), inner_(o.inner_->clone()), first_(o.first_) {}
  std::unique_ptr<graph::Factor> clone() const override { return std::make_unique<FirstEstimateJacobians>(*this); }
  std::string type() const override { return inner_->type(); }
  bool fixes_gauge() const override { return inner_->fixes_gauge(); }
  void error(const std::vector<graph::Variable>& vars, Eigen::VectorXd& e) const override { inner_->error(vars, e); }
  void linearize(const std::vector<graph::Variable>& vars, graph::Linearization& out) const override {
    std::vector<graph::Variable> at = vars;
    for (const auto& [index, value] : first_) at[static_cast<size_t>(index)] = value;
    inner_->linearize(at, out);
    inner_->error(vars, out.error);
  }

 private:
  std::unique_ptr<graph::Factor> inner_;
  std::vector<std::pair<int, graph::Variable>> first_;
};

// The initial prior's information over [rho, phi, v, b_g, b_a] of a keyframe at rotation R: position and rotation
// sigmas are given in the world frame and turned into the body-frame tangent (rho = R' dp, phi = R' dtheta).
Eigen::MatrixXd initial_information(const InertialSmootherOptions& o, const Eigen::Matrix3d& R) {
  auto inv_sq = [](double s) { return 1.0 / (s * s); };
  Eigen::MatrixXd W = Eigen::MatrixXd::Zero(15, 15);
  W.block<3, 3>(0, 0) = inv_sq(o.initial_position_sigma) * Eigen::Matrix3d::Identity();
  const Eigen::Vector3d rot(inv_sq(o.initial_tilt_sigma), inv_sq(o.initial_tilt_sigma), inv_sq(o.initial_yaw_sigma));
  W.block<3, 3>(3, 3) = symmetrized(R.transpose() * rot.asDiagonal() * R);
  W.block<3, 3>(6, 6) = inv_sq(o.initial_velocity_sigma) * Eigen::Matrix3d::Identity();
  W.block<3, 3>(9, 9) = inv_sq(o.initial_gyro_bias_sigma) * Eigen::Matrix3d::Identity();
  W.block<3, 3>(12, 12) = inv_sq(o.initial_accel_bias_sigma) * Eigen::Matrix3d::Identity();
  return W;
}

}  // namespace

void check_options(const InertialSmootherOptions& o) {
  auto positive = [](double v, const char* name) {
    if (!(v > 0) || !std::isfinite(v))
      throw std::invalid_argument(std::string("inertial smoother: ") + name + " must be positive and finite");
  };
  positive(o.keyframe_interval, "keyframe_interval");
  if (o.window < 2) throw std::invalid_argument("inertial smoother: window must be at least 2 keyframes");
  if (o.max_iterations < 1) throw std::invalid_argument("inertial smoother: max_iterations must be at least 1");
  positive(o.noise.gyro_noise_density, "noise.gyro_noise_density");
  positive(o.noise.accel_noise_density, "noise.accel_noise_density");
  positive(o.noise.gyro_bias_random_walk, "noise.gyro_bias_random_walk");
  positive(o.noise.accel_bias_random_walk, "noise.accel_bias_random_walk");
  positive(o.gnss_kernel_width, "gnss_kernel_width");
  positive(o.initial_position_sigma, "initial_position_sigma");
  positive(o.initial_velocity_sigma, "initial_velocity_sigma");
  positive(o.initial_tilt_sigma, "initial_tilt_sigma");
  positive(o.initial_yaw_sigma, "initial_yaw_sigma");
  positive(o.initial_gyro_bias_sigma, "initial_gyro_bias_sigma");
  positive(o.initial_accel_bias_sigma, "initial_accel_bias_sigma");
  positive(o.observable_tilt_sigma, "observable_tilt_sigma");
  positive(o.observable_yaw_sigma, "observable_yaw_sigma");
  if (!o.gravity.allFinite() || !o.gnss_lever_arm.allFinite())
    throw std::invalid_argument("inertial smoother: gravity and gnss_lever_arm must be finite");
}

struct InertialSmoother::State {
  InertialSmootherOptions o;
  InertialSmootherCounters counters;
  std::deque<Keyframe> keyframes;
  StoredFactor prior;                        // on the oldest keyframe
  std::vector<graph::Variable> prior_point;  // the oldest keyframe's variables where the prior was linearized
  int64_t next_seq = 0;
  // The IMU since the newest keyframe: preintegrated at its bias, the held sample and the time integrated to.
  ImuPreintegration pim;
  std::optional<BodyImuSample> held;
  double integrated_to = 0;
  // Odometry since the newest keyframe: the latest pose and the composed increment covariance from the keyframe's.
  std::optional<SE3> last_odometry;
  double last_odometry_t = 0;
  Matrix6d odometry_covariance = Matrix6d::Zero();

  explicit State(const InertialSmootherOptions& options) : o(options), pim(ImuBias{}, options.noise) {}

  const Keyframe& newest() const { return keyframes.back(); }
  KeyframeEstimate estimate(const Keyframe& k) const {
    return {k.t, nav_state(k.vars, kLocal), imu_bias(k.vars, kLocal)};
  }

  /// The window as a graph: keyframe at place w has variables 4 w .. 4 w + 3; every stored factor rebound.
  int index_of(const VariableRef& r) const {
    return static_cast<int>(r.keyframe - keyframes.front().seq) * kSlots + r.slot;
  }
  /// The factor on the graph's indices, with first-estimates Jacobians for the oldest keyframe's variables.
  std::unique_ptr<graph::Factor> rebound(const StoredFactor& f) const {
    std::vector<int> idx;
    std::vector<std::pair<int, graph::Variable>> first;
    for (const auto& r : f.variables) {
      idx.push_back(index_of(r));
      if (r.keyframe == keyframes.front().seq) first.emplace_back(idx.back(), prior_point[static_cast<size_t>(r.slot)]);
    }
    auto factor = f.factor->rebind(std::move(idx));
    if (first.empty()) return factor;
    return std::make_unique<FirstEstimateJacobians>(std::move(factor), std::move(first));
  }
  graph::FactorGraph build_graph() const {
    graph::FactorGraph g;
    for (const auto& k : keyframes)
      for (const auto& v : k.vars) g.add_variable(v);
    g.add_factor(rebound(prior));
    for (const auto& k : keyframes)
      for (const auto& f : k.factors) g.add_factor(rebound(f));
    return g;
  }

  void integrate_to(double t) {
    if (held && t > integrated_to) pim.integrate(held->gyro, held->accel, t - integrated_to);
    integrated_to = std::max(integrated_to, t);
  }

  void add_keyframe(double t, const std::optional<SE3>& odometry);
  void link_factors(Keyframe& k, const Keyframe& previous);
  void solve();
  void marginalize_oldest();
};

void InertialSmoother::State::link_factors(Keyframe& k, const Keyframe& previous) {
  auto ref = [](const Keyframe& kf, int slot) { return VariableRef{kf.seq, slot}; };
  const KeyframeVariables j_local{kSlots + kPose, kSlots + kVelocity, -1, -1};
  const std::vector<VariableRef> pair = {
      ref(previous, kPose), ref(previous, kVelocity), ref(previous, kGyroBias), ref(previous, kAccelBias),
      ref(k, kPose),        ref(k, kVelocity)};
  k.factors.push_back({std::make_unique<ImuFactor>(kLocal, j_local, pim, o.gravity), pair});
  const double dt = pim.dt();
  k.factors.push_back({std::make_unique<RandomWalkFactor>(0, 1, o.noise.gyro_bias_random_walk, dt),
                       {ref(previous, kGyroBias), ref(k, kGyroBias)}});
  k.factors.push_back({std::make_unique<RandomWalkFactor>(0, 1, o.noise.accel_bias_random_walk, dt),
                       {ref(previous, kAccelBias), ref(k, kAccelBias)}});
  if (previous.odometry && k.odometry) {
    auto f = slam::odometry_factor(false, 0, 1, previous.odometry->inverse() * *k.odometry, odometry_covariance);
    if (f) k.factors.push_back({std::move(f), {ref(previous, kPose), ref(k, kPose)}}), ++counters.odometry_links;
  }
}

void InertialSmoother::State::add_keyframe(double t, const std::optional<SE3>& odometry) {
  integrate_to(t);
  const KeyframeEstimate last = estimate(newest());
  Keyframe k;
  k.seq = next_seq;  // taken only once the keyframe is in: the window's indices count keyframes without gaps
  k.t = t;
  k.odometry = odometry;
  k.vars = keyframe_variables(k.seq, pim.predict(last.state, last.bias, o.gravity), last.bias);
  if (pim.dt() > 0) link_factors(k, newest());
  keyframes.push_back(std::move(k));
  ++next_seq;
  ++counters.keyframes;
  solve();
  if (static_cast<int>(keyframes.size()) > o.window) marginalize_oldest();
  pim.reset(imu_bias(newest().vars, kLocal));
  odometry_covariance.setZero();
}

void InertialSmoother::State::solve() {
  graph::FactorGraph g = build_graph();
  graph::OptimizerOptions oo;
  oo.method = graph::Method::kLevenbergMarquardt;
  oo.max_iterations = o.max_iterations;
  oo.fix_first_pose_if_no_gauge = false;  // the prior fixes the map frame
  if (!graph::optimize(g, oo).usable()) {
    ++counters.failed_solves;
    return;
  }
  for (size_t w = 0; w < keyframes.size(); ++w)
    for (int s = 0; s < kSlots; ++s) keyframes[w].vars[static_cast<size_t>(s)] = g.variables()[w * kSlots + s];
}

void InertialSmoother::State::marginalize_oldest() {
  // The factors touching the oldest keyframe: the prior, its fixes, and the links of the second keyframe.
  const graph::FactorGraph g = build_graph();
  std::vector<const graph::Factor*> touching;
  std::vector<StoredFactor*> stored = {&prior};
  for (auto& f : keyframes[0].factors) stored.push_back(&f);
  for (auto& f : keyframes[1].factors)
    if (!f.gnss) stored.push_back(&f);
  std::vector<std::unique_ptr<graph::Factor>> owned;
  for (StoredFactor* f : stored) {
    owned.push_back(rebound(*f));
    touching.push_back(owned.back().get());
    if (f->gnss) {
      const auto& fix = static_cast<const GnssPositionFactor&>(*f->factor);
      std::vector<graph::Variable> local;
      for (const auto& r : f->variables) local.push_back(g.variables()[static_cast<size_t>(index_of(r))]);
      if (fix.squared_error(local) > o.gnss_kernel_width * o.gnss_kernel_width) ++counters.gnss_down_weighted;
    }
  }
  auto m = graph::marginalize(g.variables(), touching, {kPose, kVelocity, kGyroBias, kAccelBias});
  if (!m) throw std::logic_error("inertial smoother: a keyframe without links to the next");
  // The new prior on the second keyframe's variables (indices 4..7 of this graph).
  std::vector<VariableRef> refs;
  for (int v : m->variables()) refs.push_back({keyframes[1].seq, v - kSlots});
  prior = {std::move(m), std::move(refs)};
  prior_point = keyframes[1].vars;
  std::vector<StoredFactor> fixes;
  for (auto& f : keyframes[1].factors)
    if (f.gnss) fixes.push_back(std::move(f));
  keyframes[1].factors = std::move(fixes);
  keyframes.pop_front();
  ++counters.marginalized;
}

// A keyframe that cannot be added (its IMU link refuses a preintegration that absurd samples made indefinite, or the
// window's solve or marginalization fails on it) must not leave the smoother half-updated nor stuck with that
// preintegration: it starts over at t from the newest keyframe that stood, carried to t at constant velocity (the
// preintegration since then is what cannot be trusted), with the options' prior.
void InertialSmoother::add_keyframe_or_restart(double t, const std::optional<SE3>& odometry) {
  const KeyframeEstimate before = s_->estimate(s_->newest());
  try {
    s_->add_keyframe(t, odometry);
  } catch (const std::exception&) {
    NavState x = before.state;
    x.p += x.v * (t - before.t);
    initialize(t, x, before.bias, odometry);
    ++s_->counters.restarts;
  }
}

InertialSmoother::InertialSmoother(const InertialSmootherOptions& options) {
  check_options(options);
  s_ = std::make_unique<State>(options);
}
InertialSmoother::~InertialSmoother() = default;
InertialSmoother::InertialSmoother(InertialSmoother&&) noexcept = default;
InertialSmoother& InertialSmoother::operator=(InertialSmoother&&) noexcept = default;

void InertialSmoother::initialize(double t, const NavState& x, const ImuBias& b, std::optional<SE3> odometry_pose,
                                  std::optional<PriorSigmas> sigmas) {
  const InertialSmootherOptions o = s_->o;
  InertialSmootherOptions prior = o;
  if (sigmas) prior.initial_position_sigma = sigmas->position, prior.initial_yaw_sigma = sigmas->yaw;
  const InertialSmootherCounters counters = s_->counters;  // they count over restarts
  s_ = std::make_unique<State>(o);
  State& s = *s_;
  s.counters = counters;
  Keyframe k;
  k.seq = s.next_seq++;
  k.t = t;
  k.odometry = odometry_pose;
  k.vars = keyframe_variables(k.seq, x, b);
  const std::vector<int> slots = {kPose, kVelocity, kGyroBias, kAccelBias};
  s.prior = {graph::LinearPriorFactor::gaussian(slots, k.vars, initial_information(prior, x.R)),
             {{k.seq, kPose}, {k.seq, kVelocity}, {k.seq, kGyroBias}, {k.seq, kAccelBias}}};
  s.prior_point = k.vars;
  s.keyframes.push_back(std::move(k));
  s.pim.reset(b);
  s.integrated_to = t;
  s.last_odometry = odometry_pose;
  s.last_odometry_t = t;
  ++s.counters.keyframes;
}

bool InertialSmoother::initialized() const { return !s_->keyframes.empty(); }

bool InertialSmoother::add_imu(double t, const BodyImuSample& sample) {
  State& s = *s_;
  if (!initialized() || !std::isfinite(t) || t < s.integrated_to || !sample.gyro.allFinite() ||
      !sample.accel.allFinite()) {
    ++s.counters.dropped;
    return false;
  }
  if (!s.held) s.held = sample;  // the first sample also covers the time since initialize()
  s.integrate_to(t);
  s.held = sample;
  ++s.counters.imu;
  const double since = t - s.newest().t;
  const bool odometry_late = s.o.use_odometry && since >= 2 * s.o.keyframe_interval;
  if ((!s.o.use_odometry && since >= s.o.keyframe_interval) || odometry_late) add_keyframe_or_restart(t, std::nullopt);
  return true;
}

bool InertialSmoother::add_odometry(double t, const SE3& pose, const Matrix6d& increment_covariance) {
  State& s = *s_;
  if (!initialized() || !s.o.use_odometry || !std::isfinite(t) || t < s.integrated_to ||
      !pose.translation().allFinite() || !increment_covariance.allFinite()) {
    ++s.counters.dropped;
    return false;
  }
  // The increment covariance composed since the newest keyframe (a first message after a gap starts afresh).
  if (s.last_odometry && s.newest().odometry)
    s.odometry_covariance =
        compose_covariance(s.odometry_covariance, s.last_odometry->inverse() * pose, increment_covariance);
  s.last_odometry = pose;
  s.last_odometry_t = t;
  ++s.counters.odometry;
  if (!s.held) return true;  // no IMU yet: nothing to preintegrate
  if (t - s.newest().t >= s.o.keyframe_interval) add_keyframe_or_restart(t, pose);
  return true;
}

bool InertialSmoother::add_gnss(double t, const Eigen::Vector3d& enu, const Eigen::Matrix3d& covariance,
                                const std::optional<Eigen::Vector3d>& lever_arm) {
  State& s = *s_;
  const Eigen::Vector3d lever = lever_arm.value_or(s.o.gnss_lever_arm);
  if (!initialized() || !std::isfinite(t) || t < s.integrated_to || !enu.allFinite() || !lever.allFinite() ||
      !is_positive_definite(covariance)) {
    ++s.counters.dropped;
    return false;
  }
  s.integrate_to(t);
  Keyframe& k = s.keyframes.back();
  StoredFactor f;
  f.gnss = true;
  if (s.pim.dt() > 0) {
    f.factor = std::make_unique<GnssPositionFactor>(kLocal, s.pim, s.o.gravity, enu, covariance, lever, s.o.gnss_kernel,
                                                    s.o.gnss_kernel_width);
    f.variables = {{k.seq, kPose}, {k.seq, kVelocity}, {k.seq, kGyroBias}, {k.seq, kAccelBias}};
  } else {
    f.factor =
        std::make_unique<GnssPositionFactor>(kPose, enu, covariance, lever, s.o.gnss_kernel, s.o.gnss_kernel_width);
    f.variables = {{k.seq, kPose}};
  }
  k.factors.push_back(std::move(f));
  ++s.counters.gnss;
  return true;
}

KeyframeEstimate InertialSmoother::newest() const { return s_->estimate(s_->newest()); }

NavState InertialSmoother::current() const {
  const KeyframeEstimate k = newest();
  return s_->pim.dt() > 0 ? s_->pim.predict(k.state, k.bias, s_->o.gravity) : k.state;
}

double InertialSmoother::current_time() const { return s_->integrated_to; }

std::vector<KeyframeEstimate> InertialSmoother::window() const {
  std::vector<KeyframeEstimate> w;
  for (const auto& k : s_->keyframes) w.push_back(s_->estimate(k));
  return w;
}

Matrix6d InertialSmoother::newest_pose_covariance() const {
  const State& s = *s_;
  const graph::FactorGraph g = s.build_graph();
  std::vector<const graph::Factor*> all;
  for (const auto& f : g.factors()) all.push_back(f.get());
  // Eliminate everything but the newest pose; its marginal information's inverse is its marginal covariance.
  const int newest_pose = static_cast<int>(s.keyframes.size() - 1) * kSlots + kPose;
  std::vector<int> others;
  for (int v = 0; v < static_cast<int>(g.variables().size()); ++v)
    if (v != newest_pose) others.push_back(v);
  const graph::MarginalInformation m = graph::marginal_information(g.variables(), all, others);
  return symmetrized(Matrix6d(m.H.inverse()));
}

Observability InertialSmoother::observability() const {
  return observability_of(newest_pose_covariance(), newest().state.R, s_->o);
}

Observability observability_of(const Matrix6d& pose_covariance, const Eigen::Matrix3d& R,
                               const InertialSmootherOptions& o) {
  const Eigen::Matrix3d world = symmetrized(R * pose_covariance.bottomRightCorner<3, 3>() * R.transpose());
  Observability out;
  out.yaw_sigma = std::sqrt(std::max(0.0, world(2, 2)));
  out.tilt_sigma = std::sqrt(std::max(
      0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(world.topLeftCorner<2, 2>()).eigenvalues().maxCoeff()));
  out.tilt = out.tilt_sigma < o.observable_tilt_sigma;
  out.yaw = out.yaw_sigma < o.observable_yaw_sigma;
  return out;
}

const InertialSmootherCounters& InertialSmoother::counters() const { return s_->counters; }

}  // namespace sextant::inertial
