#include "assoc/sd_assignment.hpp"

#include "assoc/assignment_2d.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

namespace sextant::assoc {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Detection (sensor s, index k >= 1) as one integer id.
struct DetectionIds {
  std::vector<int> offset;
  int total = 0;
  explicit DetectionIds(const std::vector<int>& n) {
    for (int c : n) offset.push_back(total), total += c;
  }
  int id(size_t s, int k) const { return offset[s] + k - 1; }
};

// Clamped at 0: when the bounds meet, rounding can put the lower one a few ulps above the upper one.
double relative_gap(double ub, double lb) { return std::abs(ub) > 1e-12 ? std::max(0.0, (ub - lb) / std::abs(ub)) : 0.0; }

// A 2-D assignment with "missed" on both sides: rows 1..R and columns 1..C of `c` (index 0 = missed), where
// c(r, 0) and c(0, k) are the costs of leaving r or k unpaired.  Returns (row, column) pairs, 0 for missed.
std::vector<std::pair<int, int>> assign_with_missed(const Eigen::MatrixXd& c, double* value) {
  const int R = static_cast<int>(c.rows()) - 1, C = static_cast<int>(c.cols()) - 1;
  Eigen::MatrixXd m = Eigen::MatrixXd::Constant(R + C, C + R, kInf);
  for (int r = 0; r < R; ++r)
    for (int k = 0; k < C; ++k) m(r, k) = c(r + 1, k + 1);
  for (int r = 0; r < R; ++r) m(r, C + r) = c(r + 1, 0);
  for (int k = 0; k < C; ++k) m(R + k, k) = c(0, k + 1);
  for (int k = 0; k < C; ++k)
    for (int r = 0; r < R; ++r) m(R + k, C + r) = 0;
  const auto a = solve_assignment_2d(m);
  std::vector<std::pair<int, int>> out;
  *value = 0;
  for (int r = 0; r < R; ++r) {
    const int k = a.column_of_row[static_cast<size_t>(r)];
    out.push_back({r + 1, k < C ? k + 1 : 0});
    *value += m(r, k);
  }
  for (int k = 0; k < C; ++k) {
    const int col = a.column_of_row[static_cast<size_t>(R + k)];
    if (col == k) out.push_back({0, k + 1}), *value += m(R + k, k);
  }
  return out;
}

}  // namespace

SdSolution solve_sd_exact(const std::vector<Tuple>& tuples, const std::vector<int>& n, long max_nodes) {
  const DetectionIds ids(n);
  std::vector<std::vector<int>> members(tuples.size()), of_detection(static_cast<size_t>(ids.total));
  for (size_t t = 0; t < tuples.size(); ++t)
    for (size_t s = 0; s < tuples[t].index.size(); ++s)
      if (tuples[t].index[s] > 0) {
        const int d = ids.id(s, tuples[t].index[s]);
        members[t].push_back(d);
        of_detection[static_cast<size_t>(d)].push_back(static_cast<int>(t));
      }
  for (auto& v : of_detection)
    std::sort(v.begin(), v.end(), [&](int a, int b) { return tuples[static_cast<size_t>(a)].cost < tuples[static_cast<size_t>(b)].cost; });
  // Per detection, the best share of a tuple's cost it can carry.
  std::vector<double> share(static_cast<size_t>(ids.total), 0.0);
  for (size_t t = 0; t < tuples.size(); ++t)
    for (int d : members[t]) share[static_cast<size_t>(d)] = std::min(share[static_cast<size_t>(d)], tuples[t].cost / static_cast<double>(members[t].size()));
  std::vector<bool> covered(static_cast<size_t>(ids.total), false);
  std::vector<int> chosen, best;
  double best_cost = 0;  // all false alarms
  long nodes = 0;
  auto recurse = [&](auto&& self, int d, double cost, double bound_rest) -> void {
    if (++nodes > max_nodes) return;
    while (d < ids.total && covered[static_cast<size_t>(d)]) ++d;  // its share left the bound when it was covered
    if (d == ids.total) {
      if (cost < best_cost) best_cost = cost, best = chosen;
      return;
    }
    if (cost + bound_rest >= best_cost - 1e-12) return;
    const double rest = bound_rest - share[static_cast<size_t>(d)];
    for (int t : of_detection[static_cast<size_t>(d)]) {
      bool free = true;
      for (int m : members[static_cast<size_t>(t)]) free = free && !covered[static_cast<size_t>(m)];
      if (!free) continue;
      double r = rest;
      for (int m : members[static_cast<size_t>(t)])
        if (m != d) covered[static_cast<size_t>(m)] = true, r -= share[static_cast<size_t>(m)];
      covered[static_cast<size_t>(d)] = true;
      chosen.push_back(t);
      self(self, d + 1, cost + tuples[static_cast<size_t>(t)].cost, r + 0.0);
      chosen.pop_back();
      for (int m : members[static_cast<size_t>(t)]) covered[static_cast<size_t>(m)] = false;
    }
    self(self, d + 1, cost, rest);  // d is a false alarm
  };
  double bound = 0;
  for (double s : share) bound += s;
  recurse(recurse, 0, 0.0, bound);
  SdSolution out;
  out.tuples = best;
  out.cost = best_cost;
  out.lower_bound = best_cost;
  out.exact = nodes <= max_nodes;
  return out;
}

SdSolution solve_sd_lagrangian(const std::vector<Tuple>& tuples, const std::vector<int>& n, int max_iterations,
                               double gap_tolerance) {
  const size_t S = n.size();
  SdSolution out;
  if (tuples.empty()) return out;
  // Multipliers u[s][k] for sensors s >= 2 (0-based), k = 1..n_s; u[s][0] = 0.
  std::vector<std::vector<double>> u(S);
  for (size_t s = 0; s < S; ++s) u[s].assign(static_cast<size_t>(n[s]) + 1, 0.0);
  double best_ub = kInf, best_lb = -kInf;
  std::vector<int> best_tuples;
  const int n1 = n[0], n2 = S > 1 ? n[1] : 0;
  for (int it = 0; it < max_iterations; ++it) {
    out.iterations = it + 1;
    // Reduced costs on (i1, i2): min over tuples of c - sum_{s>=2} u_s(i_s), with the argmin tuple.
    Eigen::MatrixXd c2 = Eigen::MatrixXd::Zero(n1 + 1, n2 + 1);  // 0: leaving a detection alone costs 0
    std::vector<int> arg(static_cast<size_t>((n1 + 1) * (n2 + 1)), -1);
    double dummy_pair = 0;  // the (0, 0) entry: every negative reduced cost may be taken
    std::vector<int> dummy_members;
    for (size_t t = 0; t < tuples.size(); ++t) {
      double r = tuples[t].cost;
      for (size_t s = 2; s < S; ++s) r -= u[s][static_cast<size_t>(tuples[t].index[s])];
      const int a = tuples[t].index[0], b = S > 1 ? tuples[t].index[1] : 0;
      if (a == 0 && b == 0) {
        if (r < 0) dummy_pair += r, dummy_members.push_back(static_cast<int>(t));
        continue;
      }
      if (r < c2(a, b)) c2(a, b) = r, arg[static_cast<size_t>(a * (n2 + 1) + b)] = static_cast<int>(t);
    }
    for (int a = 1; a <= n1; ++a)
      for (int b = 1; b <= n2; ++b)
        if (arg[static_cast<size_t>(a * (n2 + 1) + b)] < 0) c2(a, b) = kInf;
    double value = 0;
    const auto pairs = assign_with_missed(c2, &value);
    double lb = value + dummy_pair;
    for (size_t s = 2; s < S; ++s)
      for (int k = 1; k <= n[s]; ++k) lb += u[s][static_cast<size_t>(k)];
    // A detection of a relaxed sensor left alone is the singleton tuple of cost 0, reduced cost -u: the all-missed
    // pair takes it when that is negative.
    std::vector<std::vector<bool>> singleton(S);
    for (size_t s = 2; s < S; ++s) {
      singleton[s].assign(static_cast<size_t>(n[s]) + 1, false);
      for (int k = 1; k <= n[s]; ++k)
        if (u[s][static_cast<size_t>(k)] > 0) lb -= u[s][static_cast<size_t>(k)], singleton[s][static_cast<size_t>(k)] = true;
    }
    best_lb = std::max(best_lb, lb);
    // The relaxed solution's tuples, and the subgradient.
    std::vector<int> relaxed = dummy_members;
    for (auto [a, b] : pairs) {
      const int t = arg[static_cast<size_t>(a * (n2 + 1) + b)];
      if (t >= 0) relaxed.push_back(t);
    }
    std::vector<std::vector<double>> g(S);
    double g2 = 0;
    for (size_t s = 2; s < S; ++s) {
      g[s].assign(static_cast<size_t>(n[s]) + 1, 1.0);
      g[s][0] = 0;
      for (int t : relaxed) {
        const int k = tuples[static_cast<size_t>(t)].index[s];
        if (k > 0) g[s][static_cast<size_t>(k)] -= 1;
      }
      for (int k = 1; k <= n[s]; ++k)
        if (singleton[s][static_cast<size_t>(k)]) g[s][static_cast<size_t>(k)] -= 1;
      for (double x : g[s]) g2 += x * x;
    }
    // Recovery: keep the (i1, i2) pairs; add sensors 3..S one at a time by 2-D assignments over full tuples.
    std::vector<std::vector<int>> partial;  // prefixes of length 2 (only real pairs and singles)
    for (auto [a, b] : pairs) partial.push_back({a, b});
    for (size_t s = 2; s < S; ++s) {
      // Cost of extending prefix p with detection k of sensor s: the best tuple with that prefix and index
      // (its later indices free), or 0 when p stays as it is (k = 0: its detections may still become false alarms).
      std::map<std::pair<size_t, int>, std::pair<double, int>> best;
      for (size_t t = 0; t < tuples.size(); ++t) {
        for (size_t p = 0; p < partial.size(); ++p) {
          bool match = true;
          for (size_t q = 0; q < partial[p].size() && match; ++q) match = tuples[t].index[q] == partial[p][q];
          if (!match) continue;
          double r = tuples[t].cost;
          for (size_t q = s + 1; q < S; ++q) r -= u[q][static_cast<size_t>(tuples[t].index[q])];
          const auto key = std::make_pair(p, tuples[t].index[s]);
          auto itb = best.find(key);
          if (itb == best.end() || r < itb->second.first) best[key] = {r, static_cast<int>(t)};
        }
      }
      Eigen::MatrixXd c = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(partial.size()) + 1, n[s] + 1);
      for (size_t p = 0; p < partial.size(); ++p)
        for (int k = 1; k <= n[s]; ++k) {
          auto itb = best.find({p, k});
          c(static_cast<Eigen::Index>(p) + 1, k) = itb == best.end() ? kInf : itb->second.first;
        }
      for (size_t p = 0; p < partial.size(); ++p) {
        auto itb = best.find({p, 0});
        c(static_cast<Eigen::Index>(p) + 1, 0) = itb == best.end() ? 0.0 : std::min(0.0, itb->second.first);
      }
      double v = 0;
      const auto ext = assign_with_missed(c, &v);
      std::vector<std::vector<int>> next;
      for (auto [p, k] : ext) {
        std::vector<int> q = p > 0 ? partial[static_cast<size_t>(p - 1)] : std::vector<int>(s, 0);
        q.push_back(k);
        next.push_back(q);
      }
      partial = std::move(next);
    }
    // The feasible solution: prefixes that are whole tuples of the list.
    std::map<std::vector<int>, int> lookup;
    for (size_t t = 0; t < tuples.size(); ++t) lookup[tuples[t].index] = static_cast<int>(t);
    std::vector<int> feasible;
    double ub = 0;
    for (const auto& p : partial) {
      auto itl = lookup.find(p);
      if (itl != lookup.end()) feasible.push_back(itl->second), ub += tuples[static_cast<size_t>(itl->second)].cost;
    }
    if (ub < best_ub) best_ub = ub, best_tuples = feasible;
    if (relative_gap(best_ub, best_lb) < gap_tolerance || g2 == 0) break;
    const double step = (best_ub - lb) / g2;
    for (size_t s = 2; s < S; ++s)
      for (int k = 1; k <= n[s]; ++k) u[s][static_cast<size_t>(k)] += step * g[s][static_cast<size_t>(k)];
  }
  out.tuples = best_tuples;
  out.cost = best_ub;
  out.lower_bound = best_lb;
  out.gap = relative_gap(best_ub, best_lb);
  return out;
}

}  // namespace sextant::assoc
