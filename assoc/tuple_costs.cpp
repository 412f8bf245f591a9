#include "assoc/tuple_costs.hpp"

#include "assoc/bearing_model.hpp"
#include "assoc/gaussian_divergence.hpp"
#include "assoc/chi_square.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include <cmath>
#include <limits>
#include <algorithm>
#include <stdexcept>
#include <string>

namespace sextant::assoc {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Gauss-Newton steps of tuple_cost from the linear solution (the builder takes the same two for pairs).
constexpr int kReferenceSteps = 2;

double wrap(double a) {
  a = std::remainder(a, 2 * M_PI);
  return a <= -M_PI ? a + 2 * M_PI : a;
}

std::vector<BearingObservation> observations_of(const Scan& scan, const std::vector<int>& index, size_t upto) {
  std::vector<BearingObservation> obs;
  for (size_t s = 0; s < upto; ++s) {
    if (index[s] == 0) continue;
    const auto& d = scan.detections[s][static_cast<size_t>(index[s] - 1)];
    obs.push_back(
        {scan.sensors[s], d.azimuth, d.elevation,
         Eigen::Vector2d(d.sigma_azimuth * d.sigma_azimuth, d.sigma_elevation * d.sigma_elevation).asDiagonal()});
  }
  return obs;
}

double clutter_density(const CostOptions& o, size_t s) {
  return o.sensor_clutter_density.empty() ? o.clutter_density : o.sensor_clutter_density[s];
}

// The gate on the residual of a tuple of m detections: the chi-square quantile of its 2m - 3 degrees of freedom (at
// least 1) at `probability`.  build_tuples computes these once per scan (gates_by_size): the exact quantile is an
// iterative inversion, far too slow to repeat for each candidate tuple.
double residual_gate(size_t m, double probability) {
  return chi2_quantile(std::max(static_cast<int>(2 * m) - 3, 1), probability);
}

std::vector<double> gates_by_size(size_t sensors, double probability) {
  std::vector<double> gate(sensors + 1);
  for (size_t m = 0; m <= sensors; ++m) gate[m] = residual_gate(m, probability);
  return gate;
}

bool passes_gate(const Triangulation& t, double gate) { return t.valid && t.residual <= gate; }

}  // namespace

CostKind cost_kind_from_string(const std::string& s) {
  if (s == "classic") return CostKind::kClassic;
  if (s == "kl") return CostKind::kKl;
  if (s == "renyi") return CostKind::kRenyi;
  throw std::invalid_argument("unknown cost '" + s + "' (classic, kl or renyi)");
}

const char* cost_kind_name(CostKind kind) {
  switch (kind) {
    case CostKind::kClassic:
      return "classic";
    case CostKind::kKl:
      return "kl";
    case CostKind::kRenyi:
      return "renyi";
  }
  return "?";
}

namespace {

// The cost of a tuple whose detections were triangulated to `t` (valid, gate passed).  The classic term
// sum 1/2 nu' R^-1 nu is half the triangulation's residual (same R, same nu at the same position).
double cost_at(const Scan& scan, const std::vector<int>& index, const CostOptions& o, const Triangulation& t) {
  double c = 0;
  for (size_t s = 0; s < index.size(); ++s) {
    if (index[s] == 0) {
      c -= std::log(1 - o.p_detect);  // +inf when P_D = 1: every sensor must take part
      continue;
    }
    const auto& d = scan.detections[s][static_cast<size_t>(index[s] - 1)];
    const Eigen::Matrix2d R =
        Eigen::Vector2d(d.sigma_azimuth * d.sigma_azimuth, d.sigma_elevation * d.sigma_elevation).asDiagonal();
    c += -std::log(o.p_detect /
                   (clutter_density(o, s) * 2 * M_PI * d.sigma_azimuth * d.sigma_elevation));  // sqrt|2 pi R|
    if (o.kind == CostKind::kClassic) continue;
    Eigen::Matrix<double, 2, 3> J;
    const auto h = bearing(scan.sensors[s], t.position, &J);
    if (!h) return kInf;
    const Eigen::Vector2d z(d.azimuth, d.elevation);
    const Eigen::Vector2d zh(d.azimuth - wrap(d.azimuth - (*h)[0]), (*h)[1]);  // h with its azimuth unwrapped next to z
    const Eigen::Matrix2d Sh = J * t.covariance * J.transpose();
    c += o.kind == CostKind::kKl ? symmetric_kl_divergence(z, R, zh, Sh)
                                 : symmetric_renyi_divergence(z, R, zh, Sh, o.alpha) / o.alpha;
  }
  if (o.kind == CostKind::kClassic) c += 0.5 * t.residual;
  if (o.target_density > 0) c -= std::log(o.target_density * std::sqrt((2 * M_PI * t.covariance).determinant()));
  return c;
}

}  // namespace

double tuple_cost(const Scan& scan, const std::vector<int>& index, const CostOptions& o, Triangulation* out) {
  const auto obs = observations_of(scan, index, index.size());
  if (obs.size() < 2) return kInf;
  const Triangulation t = triangulate(obs, kReferenceSteps);
  if (!passes_gate(t, residual_gate(obs.size(), o.gate_probability))) return kInf;
  if (out) *out = t;
  return cost_at(scan, index, o, t);
}

namespace {

void check_scan_and_options(const Scan& scan, const CostOptions& o) {
  const size_t S = scan.sensors.size();
  if (scan.detections.size() != S)
    throw std::invalid_argument("build_tuples: " + std::to_string(scan.detections.size()) + " detection lists for " +
                                std::to_string(S) + " sensors");
  if (!o.sensor_clutter_density.empty() && o.sensor_clutter_density.size() != S)
    throw std::invalid_argument("build_tuples: " + std::to_string(o.sensor_clutter_density.size()) +
                                " per-sensor clutter densities for " + std::to_string(S) + " sensors");
  for (size_t s = 0; s < S; ++s)
    if (!(clutter_density(o, s) > 0))
      throw std::invalid_argument("build_tuples: clutter density of sensor " + std::to_string(s) + " is not positive");
}

// The tuples of one scan: the pair gate over every two sensors, then a depth-first search over the sensors that
// extends partial tuples by compatible detections.
//
// Triangulation of partial tuples, each once (no linear solve above the pairs): a pair starts from its linear
// solution and takes two Gauss-Newton steps (in the pair gate, which keeps the resulting position for the search);
// a partial tuple of m >= 3 detections starts from its parent's position (the maximum-likelihood point of m - 1 of
// its detections, already close) and takes two steps, reusing the parent's normal equations at that point (only the
// new detection is linearized there).  A complete tuple uses the triangulation of its deepest partial tuple.
class TupleBuilder {
 public:
  TupleBuilder(const Scan& scan, const CostOptions& o)
      : scan_(scan),
        o_(o),
        S_(scan.sensors.size()),
        pair_residual_gate_(chi2_quantile(1, o.gate_probability)),
        fit_of_(S_ + 1),
        gate_(gates_by_size(S_, o.gate_probability)),
        index_(S_, 0),
        candidates_(S_) {
    prepare_detections();
  }

  std::vector<Tuple> build() {
    gate_pairs();
    out_.reserve(
        2 * pair_positions_.size());  // capacity hint (tuples are mostly pairs and their extensions): no growth copies
    members_.clear();
    search(0);
    return std::move(out_);
  }

 private:
  struct Fit {
    Eigen::Vector3d x = Eigen::Vector3d::Zero();
    NormalEquations at_x;  // of the fit's detections, at x
    Triangulation t;
  };

  // Per detection: its line of sight, larger angular sigma and prepared observation (computed once).
  void prepare_detections() {
    los_.resize(S_), sigma_.resize(S_), observation_.resize(S_);
    for (size_t s = 0; s < S_; ++s)
      for (const auto& d : scan_.detections[s]) {
        los_[s].push_back(line_of_sight(d.azimuth, d.elevation));
        sigma_[s].push_back(std::max(d.sigma_azimuth, d.sigma_elevation));
        const Eigen::Vector2d var(d.sigma_azimuth * d.sigma_azimuth, d.sigma_elevation * d.sigma_elevation);
        observation_[s].emplace_back(BearingObservation{scan_.sensors[s], d.azimuth, d.elevation, var.asDiagonal()},
                                     var.cwiseInverse().asDiagonal());
      }
  }

  // The normal equations of `members_` at x.
  bool linearize(const Eigen::Vector3d& x, NormalEquations& at_x) const {
    at_x = NormalEquations{};
    for (const auto& [q, k] : members_)
      if (!add_observation(at_x, observation_[q][static_cast<size_t>(k)], x)) return false;
    return true;
  }

  // x_to = x_from + one Gauss-Newton step from the normal equations at x_from.
  static bool step(const Eigen::Vector3d& x_from, const NormalEquations& at_from, Eigen::Vector3d& x_to) {
    x_to = x_from +
           at_from.information.inverse() * at_from.gradient;  // closed-form 3 x 3 (conditioning is checked at the end)
    return x_to.allFinite();
  }

  // f.x = two steps from `start` (normal equations `at_start` there), f.at_x and f.t at f.x; false when degenerate.
  bool fit_from(const Eigen::Vector3d& start, const NormalEquations& at_start, Fit& f) const {
    Eigen::Vector3d x1;
    NormalEquations at_x1;
    if (!step(start, at_start, x1) || !linearize(x1, at_x1) || !step(x1, at_x1, f.x) || !linearize(f.x, f.at_x))
      return false;
    f.t = triangulation_at(f.x, f.at_x);
    return f.t.valid;
  }

  // The pair `members_`: its linear solution, one step, the chi-square gate on the residual there (as
  // triangulate(pair, 1)), and the second step's position into x2; false when gated out or degenerate.
  bool gate_pair(Eigen::Vector3d& x2) const {
    const PreparedBearing& a = observation_[members_[0].first][static_cast<size_t>(members_[0].second)];
    const PreparedBearing& b = observation_[members_[1].first][static_cast<size_t>(members_[1].second)];
    const Triangulation lin =
        triangulate_linear(a.linear_information + b.linear_information, a.linear_rhs + b.linear_rhs);
    Eigen::Vector3d x1;
    NormalEquations at_x0, at_x1;
    return lin.valid && linearize(lin.position, at_x0) && step(lin.position, at_x0, x1) && linearize(x1, at_x1) &&
           at_x1.residual <= pair_residual_gate_ && step(x1, at_x1, x2);
  }

  // Pair gate.  The closest approach of the two lines of sight must lie in front of both sensors, and the miss
  // distance within 2 sqrt(chi2_1) times the cross-range noise at those ranges (a loose pre-test: the residual of
  // the pair's triangulation is about miss^2 / (sigma_s^2 r_s^2 + sigma_t^2 r_t^2) <= chi2_1); then the chi-square
  // gate on the residual of the pair's fit after one Gauss-Newton step from its linear solution (gate_pair; a
  // complete pair tuple is gated again on its final fit).  compatible_[s][t][k] = the detections j of sensor t
  // (1-based, sorted) that pass with (s, k); for s < t, pair_fit_[s][t][k] = the positions of their two-step
  // positions in `pair_positions_` (only the position is kept: 24 bytes a pair, the search linearizes there).
  void gate_pairs() {
    const double pair_gate = 2 * std::sqrt(chi2_quantile(1, o_.gate_probability));
    compatible_.assign(S_, std::vector<std::vector<std::vector<int>>>(S_));
    pair_fit_ = compatible_;
    for (size_t s = 0; s < S_; ++s)
      for (size_t t = s + 1; t < S_; ++t) {
        const size_t ns = scan_.detections[s].size(), nt = scan_.detections[t].size();
        compatible_[s][t].assign(ns + 1, {});
        pair_fit_[s][t].assign(ns + 1, {});
        compatible_[t][s].assign(nt + 1, {});
        const Eigen::Vector3d w = scan_.sensors[s] - scan_.sensors[t];
        for (size_t k = 0; k < ns; ++k)
          for (size_t j = 0; j < nt; ++j) {
            const Eigen::Vector3d &us = los_[s][k], &ut = los_[t][j];
            const double b = us.dot(ut), d = us.dot(w), e = ut.dot(w), den = 1 - b * b;
            if (den < 1e-12) continue;  // parallel lines of sight
            const double rs = (b * e - d) / den, rt = (e - b * d) / den;
            if (!(rs > 0 && rt > 0)) continue;
            const double miss = (w + rs * us - rt * ut).norm();
            if (miss > pair_gate * (sigma_[s][k] * rs + sigma_[t][j] * rt)) continue;
            members_ = {{s, static_cast<int>(k)}, {t, static_cast<int>(j)}};
            Eigen::Vector3d x2;
            if (!gate_pair(x2)) continue;
            compatible_[s][t][k + 1].push_back(static_cast<int>(j) + 1);
            pair_fit_[s][t][k + 1].push_back(static_cast<int>(pair_positions_.size()));
            compatible_[t][s][j + 1].push_back(static_cast<int>(k) + 1);
            pair_positions_.push_back(x2);
          }
      }
  }

  // Fits the partial tuple `members_` (m >= 3) from its parent's fit into fit_of_[m].
  bool extend(size_t m) {
    const Fit& parent = fit_of_[m - 1];
    NormalEquations at_parent = parent.at_x;
    const auto [q, k] = members_.back();
    if (!add_observation(at_parent, observation_[q][static_cast<size_t>(k)], parent.x)) return false;
    return fit_from(parent.x, at_parent, fit_of_[m]);
  }

  // The detections of sensor s that may join the current partial tuple, with their pair fit with its first
  // detection (-1 when it has none yet: every detection): those compatible with each of its detections.
  void collect_candidates(size_t s) {
    auto& cand = candidates_[s];
    cand.clear();
    if (real_.empty()) {
      for (int k = 1; k <= static_cast<int>(scan_.detections[s].size()); ++k) cand.push_back({k, -1});
      return;
    }
    const size_t r0 = real_.front();
    const auto& first = compatible_[r0][s][static_cast<size_t>(index_[r0])];
    const auto& first_fit = pair_fit_[r0][s][static_cast<size_t>(index_[r0])];
    for (size_t i = 0; i < first.size(); ++i) {
      const int k = first[i];
      bool ok = true;
      for (size_t q = 1; q < real_.size() && ok; ++q) {
        const auto& list = compatible_[real_[q]][s][static_cast<size_t>(index_[real_[q]])];
        ok = std::binary_search(list.begin(), list.end(), k);
      }
      if (ok) cand.push_back({k, first_fit[i]});
    }
  }

  // The fit of the partial tuple just grown to m detections (a pair from its gated position, a larger one from its
  // parent's fit); partial tuples of >= 3 detections pass the residual gate before being extended.
  bool fit_partial(size_t m, int pair) {
    if (m == 2) {
      Fit& f = fit_of_[2];
      f.x = pair_positions_[static_cast<size_t>(pair)];
      return linearize(f.x, f.at_x) && (f.t = triangulation_at(f.x, f.at_x)).valid;
    }
    if (m >= 3) return extend(m) && passes_gate(fit_of_[m].t, gate_[m]);
    return true;
  }

  // A complete tuple: gated on its fit, kept when its cost is negative.
  void add_complete() {
    const Triangulation& t = fit_of_[real_.size()].t;
    if (!passes_gate(t, gate_[real_.size()])) return;
    const double c = cost_at(scan_, index_, o_, t);
    if (c < 0) out_.push_back({index_, c, t.position, t.covariance});
  }

  // Depth-first over the sensors from sensor s: a detection joins a partial tuple only when it is compatible with
  // each of its detections.
  void search(size_t s) {
    if (real_.size() + (S_ - s) < 2) return;  // cannot reach two detections any more
    if (s == S_) return add_complete();
    index_[s] = 0;
    if (o_.p_detect < 1) search(s + 1);  // with P_D = 1 a missed index costs +infinity
    collect_candidates(s);
    for (const auto& [k, pair] : candidates_[s]) {
      index_[s] = k;
      members_.push_back({s, k - 1});
      real_.push_back(s);
      if (fit_partial(real_.size(), pair)) search(s + 1);
      real_.pop_back();
      members_.pop_back();
    }
    index_[s] = 0;
  }

  const Scan& scan_;
  const CostOptions& o_;
  const size_t S_;
  const double pair_residual_gate_;
  std::vector<std::vector<Eigen::Vector3d>> los_;
  std::vector<std::vector<double>> sigma_;
  std::vector<std::vector<PreparedBearing>> observation_;
  std::vector<std::pair<size_t, int>> members_;  // (sensor, 0-based detection) of the partial tuple being fitted
  using Lists = std::vector<std::vector<std::vector<std::vector<int>>>>;
  Lists compatible_, pair_fit_;
  std::vector<Eigen::Vector3d> pair_positions_;
  std::vector<Fit> fit_of_;         // the current partial tuple's fit, by its number of detections
  const std::vector<double> gate_;  // residual gate by number of detections
  std::vector<Tuple> out_;
  std::vector<int> index_;
  std::vector<size_t> real_;                                  // sensors with a detection in the partial tuple
  std::vector<std::vector<std::pair<int, int>>> candidates_;  // per depth: (detection, its pair fit or -1)
};

}  // namespace

std::vector<Tuple> build_tuples(const Scan& scan, const CostOptions& o) {
  check_scan_and_options(scan, o);
  return TupleBuilder(scan, o).build();
}

}  // namespace sextant::assoc
