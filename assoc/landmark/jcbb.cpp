#include "assoc/landmark/jcbb.hpp"

#include <Eigen/Cholesky>

#include <cmath>
#include <limits>

namespace sextant::assoc {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Standard normal quantile (Acklam's rational approximation, |error| < 1.2e-9).
double normal_quantile(double p) {
  static const double a[] = {-3.969683028665376e+01, 2.209460984245205e+02, -2.759285104469687e+02,
                             1.383577518672690e+02, -3.066479806614716e+01, 2.506628277459239e+00};
  static const double b[] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02,
                             6.680131188771972e+01, -1.328068155288572e+01};
  static const double c[] = {-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00,
                             -2.549732539343734e+00, 4.374664141464968e+00, 2.938163982698783e+00};
  static const double d[] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00, 3.754408661907416e+00};
  if (p < 0.02425) {
    const double q = std::sqrt(-2 * std::log(p));
    return (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) / ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
  }
  if (p > 1 - 0.02425) return -normal_quantile(1 - p);
  const double q = p - 0.5, r = q * q;
  return (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
         (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1);
}

struct Search {
  const AssociationProblem& p;
  std::vector<std::vector<int>> compatible;  // per sighting: individually compatible landmarks
  Hypothesis best, current;
  int best_pairs = -1;
  double best_d2 = kInf;
  int nodes = 0, max_nodes;

  // Joint D2 of the pairs in `current` (those != -1).
  double joint(int* dim) const { return joint_distance(p, current, dim); }

  void recurse(int i, int pairs) {
    if (++nodes > max_nodes) return;
    if (i == p.sightings) {
      if (pairs == 0) return;
      const double d2 = joint(nullptr);
      if (pairs > best_pairs || (pairs == best_pairs && d2 < best_d2)) best = current, best_pairs = pairs, best_d2 = d2;
      return;
    }
    for (int j : compatible[static_cast<size_t>(i)]) {
      bool used = false;
      for (int k = 0; k < i; ++k) used = used || current[static_cast<size_t>(k)] == j;
      if (used) continue;
      current[static_cast<size_t>(i)] = j;
      int dim = 0;
      const double d2 = joint(&dim);
      if (d2 < chi2_quantile(dim, p.joint_gate_probability)) recurse(i + 1, pairs + 1);
      current[static_cast<size_t>(i)] = -1;
    }
    // Leave sighting i unpaired only if that can still beat the best (branch and bound on the pair count).
    if (pairs + (p.sightings - i - 1) >= best_pairs) recurse(i + 1, pairs);
  }
};

}  // namespace

double chi2_quantile(int dof, double probability) {
  if (dof <= 0) return 0;
  const double k = dof, z = normal_quantile(probability);
  const double t = 1 - 2 / (9 * k) + z * std::sqrt(2 / (9 * k));
  return k * t * t * t;
}

double individual_distance(const AssociationProblem& p, int i, int j) {
  const auto c = p.candidate(i, j);
  if (!c) return kInf;
  const Eigen::MatrixXd S = c->jacobian * (*p.covariance) * c->jacobian.transpose() + p.noise[static_cast<size_t>(i)];
  const Eigen::LLT<Eigen::MatrixXd> llt(S);
  if (llt.info() != Eigen::Success) return kInf;
  return c->innovation.dot(llt.solve(c->innovation));
}

double joint_distance(const AssociationProblem& p, const Hypothesis& h, int* dimension) {
  std::vector<Candidate> pairs;
  std::vector<int> rows;
  int dim = 0;
  for (size_t i = 0; i < h.size(); ++i) {
    if (h[i] < 0) continue;
    auto c = p.candidate(static_cast<int>(i), h[i]);
    if (!c) return kInf;
    dim += static_cast<int>(c->innovation.size());
    rows.push_back(static_cast<int>(i));
    pairs.push_back(std::move(*c));
  }
  if (dimension) *dimension = dim;
  if (dim == 0) return 0;
  const Eigen::Index n = p.covariance->rows();
  Eigen::VectorXd nu(dim);
  Eigen::MatrixXd H(dim, n), R = Eigen::MatrixXd::Zero(dim, dim);
  int r = 0;
  for (size_t k = 0; k < pairs.size(); ++k) {
    const auto d = pairs[k].innovation.size();
    nu.segment(r, d) = pairs[k].innovation;
    H.middleRows(r, d) = pairs[k].jacobian;
    R.block(r, r, d, d) = p.noise[static_cast<size_t>(rows[k])];
    r += static_cast<int>(d);
  }
  const Eigen::MatrixXd S = H * (*p.covariance) * H.transpose() + R;
  const Eigen::LLT<Eigen::MatrixXd> llt(S);
  if (llt.info() != Eigen::Success) return kInf;
  return nu.dot(llt.solve(nu));
}

Hypothesis nearest_neighbour(const AssociationProblem& p) {
  Hypothesis h(static_cast<size_t>(p.sightings), -1);
  std::vector<bool> used(static_cast<size_t>(p.landmarks), false);
  for (int i = 0; i < p.sightings; ++i) {
    double best = p.individual_gate;
    for (int j = 0; j < p.landmarks; ++j) {
      if (used[static_cast<size_t>(j)]) continue;
      const double d2 = individual_distance(p, i, j);
      if (d2 < best) best = d2, h[static_cast<size_t>(i)] = j;
    }
    if (h[static_cast<size_t>(i)] >= 0) used[static_cast<size_t>(h[static_cast<size_t>(i)])] = true;
  }
  return h;
}

Hypothesis joint_compatibility_branch_and_bound(const AssociationProblem& p, int max_nodes) {
  Search s{p, {}, {}, Hypothesis(static_cast<size_t>(p.sightings), -1), -1, kInf, 0, max_nodes};
  s.compatible.resize(static_cast<size_t>(p.sightings));
  for (int i = 0; i < p.sightings; ++i)
    for (int j = 0; j < p.landmarks; ++j)
      if (individual_distance(p, i, j) < p.individual_gate) s.compatible[static_cast<size_t>(i)].push_back(j);
  s.best = s.current;
  s.recurse(0, 0);
  return s.best;
}

}  // namespace sextant::assoc
