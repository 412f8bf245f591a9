#include "assoc/landmark/jcbb.hpp"

#include "assoc/chi_square.hpp"

#include <Eigen/Cholesky>

#include <cmath>
#include <limits>

namespace sextant::assoc {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

struct Search {
  const AssociationProblem& p;
  std::vector<std::vector<int>> compatible;  // per sighting: individually compatible landmarks
  Hypothesis best, current;
  int best_pairs = -1;
  double best_d2 = kInf;
  int nodes = 0, max_nodes;
  std::vector<double> gates{};  // joint gate by dimension, computed on first use (the exact quantile is iterative)

  double gate(int dim) {
    if (static_cast<size_t>(dim) >= gates.size()) gates.resize(static_cast<size_t>(dim) + 1, -1.0);
    double& g = gates[static_cast<size_t>(dim)];
    if (g < 0) g = chi2_quantile(dim, p.joint_gate_probability);
    return g;
  }

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
      if (d2 < gate(dim)) recurse(i + 1, pairs + 1);
      current[static_cast<size_t>(i)] = -1;
    }
    // Leave sighting i unpaired only if that can still beat the best (branch and bound on the pair count).
    if (pairs + (p.sightings - i - 1) >= best_pairs) recurse(i + 1, pairs);
  }
};

}  // namespace

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
