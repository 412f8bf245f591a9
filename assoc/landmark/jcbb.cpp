#include "assoc/landmark/jcbb.hpp"

#include "assoc/chi_square.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>
#include <limits>

namespace sextant::assoc {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// The stacked innovation nu, Jacobian columns H_c over the state columns `cols`, noise R, and the cost of forming
// and factorizing S = H_c P(cols, cols) H_c' + R.
struct Stacked {
  Eigen::VectorXd nu;
  Eigen::MatrixXd H;
  std::vector<Eigen::Index> cols;  // empty: all n columns
  Eigen::MatrixXd R;
};

double cost(Eigen::Index d, Eigen::Index k) {
  const auto dd = static_cast<double>(d), kk = static_cast<double>(k);
  return dd * kk * kk + dd * dd * kk + dd * dd * dd + 64;
}

// d2 = nu' S^-1 nu for a stacked set of candidates (infinity when S is not positive definite).
double mahalanobis(const AssociationProblem& p, const Stacked& s) {
  Eigen::MatrixXd S;
  if (s.cols.empty()) {
    S = s.H * (*p.covariance) * s.H.transpose() + s.R;
  } else {
    const auto k = static_cast<Eigen::Index>(s.cols.size());
    Eigen::MatrixXd Psub(k, k);
    for (Eigen::Index a = 0; a < k; ++a)
      for (Eigen::Index b = 0; b < k; ++b)
        Psub(a, b) = (*p.covariance)(s.cols[static_cast<size_t>(a)], s.cols[static_cast<size_t>(b)]);
    S = s.H * Psub * s.H.transpose() + s.R;
  }
  const Eigen::LLT<Eigen::MatrixXd> llt(S);
  if (llt.info() != Eigen::Success) return kInf;
  const double d2 = s.nu.dot(llt.solve(s.nu));
  return std::isfinite(d2) ? d2 : kInf;
}

// Stacks the candidates of the pairs (sighting rows[k], candidate pairs[k]); sparse columns are merged.
Stacked stack(const AssociationProblem& p, const std::vector<Candidate>& pairs, const std::vector<int>& rows) {
  Stacked s;
  bool dense = false;
  Eigen::Index dim = 0;
  for (const Candidate& c : pairs) {
    dim += c.innovation.size();
    dense = dense || c.columns.empty();
    s.cols.insert(s.cols.end(), c.columns.begin(), c.columns.end());
  }
  const Eigen::Index n = p.covariance->rows();
  if (dense) s.cols.clear();
  std::sort(s.cols.begin(), s.cols.end());
  s.cols.erase(std::unique(s.cols.begin(), s.cols.end()), s.cols.end());
  s.nu.resize(dim);
  s.H = Eigen::MatrixXd::Zero(dim, dense ? n : static_cast<Eigen::Index>(s.cols.size()));
  s.R = Eigen::MatrixXd::Zero(dim, dim);
  Eigen::Index r = 0;
  for (size_t k = 0; k < pairs.size(); ++k) {
    const Candidate& c = pairs[k];
    const auto d = c.innovation.size();
    s.nu.segment(r, d) = c.innovation;
    s.R.block(r, r, d, d) = p.noise[static_cast<size_t>(rows[k])];
    if (c.columns.empty()) {
      s.H.middleRows(r, d) = c.jacobian;
    } else {
      for (size_t a = 0; a < c.columns.size(); ++a) {
        const auto col =
            dense ? c.columns[a] : std::lower_bound(s.cols.begin(), s.cols.end(), c.columns[a]) - s.cols.begin();
        s.H.block(r, col, d, 1) = c.jacobian.col(static_cast<Eigen::Index>(a));
      }
    }
    r += d;
  }
  return s;
}

Eigen::Index width(const AssociationProblem& p, const Stacked& s) {
  return s.cols.empty() ? p.covariance->rows() : static_cast<Eigen::Index>(s.cols.size());
}

struct Search {
  const AssociationProblem& p;
  std::vector<std::vector<std::pair<int, double>>> compatible;  // per sighting: (landmark, D2) individually compatible
  Hypothesis best, current;
  int best_pairs = -1;
  double best_d2 = kInf;
  int nodes = 0, max_nodes;
  double work = 0;
  bool exhausted = false;
  std::vector<double> gates{};  // joint gate by dimension, computed on first use (the exact quantile is iterative)

  bool over_budget() {
    if (p.work_budget > 0 && work > p.work_budget) exhausted = true;
    return exhausted;
  }

  double gate(int dim) {
    if (static_cast<size_t>(dim) >= gates.size()) gates.resize(static_cast<size_t>(dim) + 1, -1.0);
    double& g = gates[static_cast<size_t>(dim)];
    if (g < 0) g = chi2_quantile(dim, p.joint_gate_probability);
    return g;
  }

  // Joint D2 of the pairs in `current` (those != -1), charged to the budget.
  double joint(int* dim) {
    std::vector<Candidate> pairs;
    std::vector<int> rows;
    for (size_t i = 0; i < current.size(); ++i) {
      if (current[i] < 0) continue;
      auto c = p.candidate(static_cast<int>(i), current[i]);
      if (!c) return kInf;
      rows.push_back(static_cast<int>(i));
      pairs.push_back(std::move(*c));
    }
    const Stacked s = stack(p, pairs, rows);
    if (dim) *dim = static_cast<int>(s.nu.size());
    if (s.nu.size() == 0) return 0;
    work += cost(s.nu.size(), width(p, s)) + 64.0 * static_cast<double>(pairs.size());
    return mahalanobis(p, s);
  }

  void recurse(int i, int pairs) {
    if (++nodes > max_nodes || over_budget()) return;
    if (i == p.sightings) {
      if (pairs == 0) return;
      const double d2 = joint(nullptr);
      if (pairs > best_pairs || (pairs == best_pairs && d2 < best_d2)) best = current, best_pairs = pairs, best_d2 = d2;
      return;
    }
    for (const auto& [j, d2_individual] : compatible[static_cast<size_t>(i)]) {
      bool used = false;
      for (int k = 0; k < i; ++k) used = used || current[static_cast<size_t>(k)] == j;
      if (used) continue;
      current[static_cast<size_t>(i)] = j;
      int dim = 0;
      const double d2 = joint(&dim);
      if (d2 < gate(dim)) recurse(i + 1, pairs + 1);
      current[static_cast<size_t>(i)] = -1;
      if (exhausted) return;
    }
    // Leave sighting i unpaired only if that can still beat the best (branch and bound on the pair count).
    if (pairs + (p.sightings - i - 1) >= best_pairs) recurse(i + 1, pairs);
  }

  // Nearest neighbour over the compatibility lists (each landmark once, sightings in order).
  Hypothesis nearest() const {
    Hypothesis h(static_cast<size_t>(p.sightings), -1);
    std::vector<bool> used(static_cast<size_t>(p.landmarks), false);
    for (size_t i = 0; i < compatible.size(); ++i) {
      double best_here = kInf;
      for (const auto& [j, d2] : compatible[i])
        if (!used[static_cast<size_t>(j)] && d2 < best_here) best_here = d2, h[i] = j;
      if (h[i] >= 0) used[static_cast<size_t>(h[i])] = true;
    }
    return h;
  }
};

}  // namespace

double individual_distance(const AssociationProblem& p, int i, int j) {
  const auto c = p.candidate(i, j);
  if (!c) return kInf;
  return mahalanobis(p, stack(p, {*c}, {i}));
}

double joint_distance(const AssociationProblem& p, const Hypothesis& h, int* dimension) {
  std::vector<Candidate> pairs;
  std::vector<int> rows;
  for (size_t i = 0; i < h.size(); ++i) {
    if (h[i] < 0) continue;
    auto c = p.candidate(static_cast<int>(i), h[i]);
    if (!c) return kInf;
    rows.push_back(static_cast<int>(i));
    pairs.push_back(std::move(*c));
  }
  const Stacked s = stack(p, pairs, rows);
  if (dimension) *dimension = static_cast<int>(s.nu.size());
  if (s.nu.size() == 0) return 0;
  return mahalanobis(p, s);
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

BoundedAssociation associate_bounded(const AssociationProblem& p, int max_nodes) {
  Search s{p, {}, {}, Hypothesis(static_cast<size_t>(p.sightings), -1), -1, kInf, 0, max_nodes};
  s.compatible.resize(static_cast<size_t>(p.sightings));
  BoundedAssociation out;
  // Step 1: individual compatibility, sighting by sighting, while the budget lasts.
  for (int i = 0; i < p.sightings && !s.exhausted; ++i) {
    for (int j = 0; j < p.landmarks; ++j) {
      const auto c = p.candidate(i, j);
      if (!c) continue;
      const Stacked one = stack(p, {*c}, {i});
      s.work += cost(one.nu.size(), width(p, one));
      if (const double d2 = mahalanobis(p, one); d2 < p.individual_gate)
        s.compatible[static_cast<size_t>(i)].push_back({j, d2});
      if (s.over_budget()) break;
    }
    if (s.exhausted)
      s.compatible[static_cast<size_t>(i)].clear();  // not fully examined: no pairing
    else
      out.examined = i + 1;
  }
  // Step 2: the search, or nearest neighbour when the budget is gone.
  s.best = s.current;
  if (!s.exhausted) s.recurse(0, 0);
  out.exhausted = s.exhausted;
  out.pairing = s.exhausted ? s.nearest() : s.best;
  out.work = s.work;
  if (p.sightings == 0) out.examined = 0;
  return out;
}

Hypothesis joint_compatibility_branch_and_bound(const AssociationProblem& p, int max_nodes) {
  return associate_bounded(p, max_nodes).pairing;
}

}  // namespace sextant::assoc
