#include "assoc/sd_assignment.hpp"

#include "assoc/assignment_with_missed.hpp"
#include "assoc/packing_branch_and_bound.hpp"
#include "assoc/sensor_reassignment.hpp"
#include "assoc/tuple_packing.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>

namespace sextant::assoc {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPromising = 0.0;  // relative margin above the best upper bound for a recovery to be improved
// Iterations without a better lower bound before the step factor is halved (10 rather than 5 once the multipliers
// start at the equal shares: LR optimality on the unit test's 300 instances 299 instead of 298, same iterations;
// RESULTS, session 4).
constexpr int kStallLimit = 10;
// Components with at most this many detections are solved exactly by the branch and bound (a few hundred nodes at
// most, less work than one relaxation iteration on a scan), within kSmallComponentNodes nodes (the relaxation
// takes over if they run out).  Why: the relaxation's bound is the packing LP's, and on the smallest components
// the LP is often fractional.  The typical one is three detections, one per sensor, with the three pairs but no
// triple worth more: x = 1/2 on each pair is an LP solution a third better than any assignment.  Such a
// component's bound can never be closed, and its absolute gap pushed the scan's total gap over the tolerance on 5
// of the 6 grid scans in 1000 that ended above 1 % (RESULTS, passive association session 6).
constexpr int kSmallComponentDetections = 8;
constexpr long kSmallComponentNodes = 100'000;
// A component whose gap is still above the tolerance after the iteration limit is solved again with another sensor
// relaxed (the sensor order rotated by one, then by two): the recovery then fixes a different pair of sensors from
// the relaxed solution, so it reaches pairings the first run's recovery and local search could not (with the
// target prior, the stalled scans' upper bounds were 0.8-1.7 % above the optimum while the lower bound sat at the
// LP bound).  Only the stalled components pay for it.
constexpr size_t kExtraRotations = 2;
// A component whose gap is still open after the rotations goes to the branch and bound
// (packing_branch_and_bound.hpp) from the relaxation's best solution, bounded by the relaxation at its best
// multipliers (RelaxationBound below), within this many nodes.  Coplanar grid, P_D 1, 100 scans per spacing: the
// optimum on 100/100 at d = 0.5, 1.0 and 1.5 km with 2000 or 20000 nodes alike (RESULTS, "Correct by default").
constexpr long kFallbackNodes = 2000;
// solve_sd_exact: relaxation iterations for the incumbent and the multipliers of the branch and bound's bound.
constexpr int kExactIterations = 300;
// ... stopping when its gap is below this (cost units): the branch and bound then proves the rest.  With 0 the
// bounds, which meet only up to rounding, kept it running to the limit on every component.
constexpr double kExactGap = 1e-9;

// Clamped at 0: when the bounds meet, rounding can put the lower one a few ulps above the upper one.
double relative_gap(double ub, double lb) { return std::abs(ub) > 1e-12 ? std::max(0.0, (ub - lb) / std::abs(ub)) : 0.0; }

// The caller's tuples as detection sets (detection (s, k >= 1) has id offset[s] + k - 1).
TuplePacking packing_of(const std::vector<Tuple>& tuples, const std::vector<int>& n) {
  std::vector<int> offset;
  TuplePacking p;
  for (int c : n) offset.push_back(p.detections), p.detections += c;
  p.ids.reserve(tuples.size() * n.size());
  std::vector<int> m;
  for (const auto& t : tuples) {
    if (t.index.size() != n.size())
      throw std::invalid_argument("S-D assignment: a tuple has " + std::to_string(t.index.size()) + " indices for " +
                                  std::to_string(n.size()) + " sensors");
    m.clear();
    for (size_t s = 0; s < n.size(); ++s) {
      if (t.index[s] < 0 || t.index[s] > n[s])
        throw std::invalid_argument("S-D assignment: index " + std::to_string(t.index[s]) + " of sensor " +
                                    std::to_string(s) + " outside 0.." + std::to_string(n[s]));
      if (t.index[s] > 0) m.push_back(offset[s] + t.index[s] - 1);
    }
    p.add(m, t.cost);
  }
  return p;
}

// The sub-problem of one component, with detection ids renumbered 0..d-1.
TuplePacking restrict_to(const TuplePacking& all, const std::vector<int>& group) {
  TuplePacking p;
  std::vector<int> local(static_cast<size_t>(all.detections), -1), m;
  for (int t : group) {
    m.clear();
    for (int d : all.members(static_cast<size_t>(t))) {
      int& l = local[static_cast<size_t>(d)];
      if (l < 0) l = p.detections++;
      m.push_back(l);
    }
    p.add(m, all.cost[static_cast<size_t>(t)]);
  }
  return p;
}

// One component exactly (packing_branch_and_bound.hpp): the incumbent is `start` (or, when empty, the greedy
// cheapest-first packing) improved by exchange moves; the multipliers are the equal shares raised by
// `dual_iterations` subgradient steps on the packing's Lagrangian.  `nodes` counts against the caller's budget.
PackingSolution solve_exactly(const TuplePacking& p, std::vector<int> start, long max_nodes, long& nodes, int dual_iterations) {
  if (start.empty()) {
    std::vector<int> order(p.size());
    for (size_t t = 0; t < p.size(); ++t) order[t] = static_cast<int>(t);
    std::sort(order.begin(), order.end(), [&](int a, int b) { return p.cost[static_cast<size_t>(a)] < p.cost[static_cast<size_t>(b)]; });
    std::vector<char> used(static_cast<size_t>(p.detections), 0);
    for (int t : order) {
      const auto m = p.members(static_cast<size_t>(t));
      if (p.cost[static_cast<size_t>(t)] >= 0 || std::any_of(m.begin(), m.end(), [&](int d) { return used[static_cast<size_t>(d)]; })) continue;
      for (int d : m) used[static_cast<size_t>(d)] = 1;
      start.push_back(t);
    }
  }
  const double ub = improve_by_exchange(p, start, 20);
  std::vector<double> v = equal_share_multipliers(p);
  maximize_packing_lagrangian(p, v, ub, dual_iterations);
  auto sol = solve_packing_exactly(p, start, v, std::max(0L, max_nodes - nodes));
  nodes += sol.nodes;
  return sol;
}

// One component restated for the relaxation: only the sensors that have detections in it, ordered by decreasing
// detection count, detections renumbered 1..n_s, tuples sorted lexicographically by their indices, which are
// stored flat (tuple t's index at sensor s is index[t * S + s]).
struct RelaxationProblem {
  size_t S = 0;                // sensors
  std::vector<int> n;          // detections per (reordered) sensor
  std::vector<int> index;      // per tuple, S indices; rows sorted
  std::vector<double> cost;
  std::vector<int> original;   // position in the component's group
  TuplePacking packing;        // the same tuples (same order) as detection sets

  /// `rotation`: the sensors, ordered by decreasing detection count, are rotated left by this many places (the
  /// first two are the relaxed problem's, the others are relaxed).
  RelaxationProblem(const std::vector<Tuple>& tuples, const std::vector<int>& group, const std::vector<int>& detections,
                    size_t rotation = 0) {
    const size_t all_sensors = detections.size();
    // Per original sensor, the new number of each of its detections used in the group (0: unused).
    std::vector<std::vector<int>> renumbered(all_sensors);
    for (size_t s = 0; s < all_sensors; ++s) renumbered[s].assign(static_cast<size_t>(detections[s]) + 1, 0);
    for (int t : group)
      for (size_t s = 0; s < all_sensors; ++s)
        if (const int k = tuples[static_cast<size_t>(t)].index[s]; k > 0) renumbered[s][static_cast<size_t>(k)] = 1;
    std::vector<size_t> sensors;
    std::vector<int> used(all_sensors, 0);
    for (size_t s = 0; s < all_sensors; ++s) {
      for (size_t k = 1; k < renumbered[s].size(); ++k)
        if (renumbered[s][k]) renumbered[s][k] = ++used[s];
      if (used[s] > 0) sensors.push_back(s);
    }
    std::stable_sort(sensors.begin(), sensors.end(), [&](size_t a, size_t b) { return used[a] > used[b]; });
    if (!sensors.empty()) std::rotate(sensors.begin(), sensors.begin() + static_cast<long>(rotation % sensors.size()), sensors.end());
    S = sensors.size();
    for (size_t s : sensors) n.push_back(used[s]);
    const size_t T = group.size();
    std::vector<int> rows(T * S);
    for (size_t i = 0; i < T; ++i)
      for (size_t q = 0; q < S; ++q) {
        const size_t s = sensors[q];
        rows[i * S + q] = renumbered[s][static_cast<size_t>(tuples[static_cast<size_t>(group[i])].index[s])];
      }
    std::vector<int> order(T);
    for (size_t i = 0; i < T; ++i) order[i] = static_cast<int>(i);
    std::sort(order.begin(), order.end(), [&](int a, int b) {
      const int* ra = rows.data() + static_cast<size_t>(a) * S;
      const int* rb = rows.data() + static_cast<size_t>(b) * S;
      return std::lexicographical_compare(ra, ra + S, rb, rb + S);
    });
    std::vector<int> offset;
    for (int c : n) offset.push_back(packing.detections), packing.detections += c;
    index.reserve(T * S);
    std::vector<int> m;
    for (int i : order) {
      const int* r = rows.data() + static_cast<size_t>(i) * S;
      index.insert(index.end(), r, r + S);
      cost.push_back(tuples[static_cast<size_t>(group[static_cast<size_t>(i)])].cost);
      original.push_back(i);
      m.clear();
      for (size_t q = 0; q < S; ++q)
        if (r[q] > 0) m.push_back(offset[q] + r[q] - 1);
      packing.add(m, cost.back());
    }
  }

  size_t sensors() const { return S; }
  size_t size() const { return cost.size(); }
  int at(size_t t, size_t s) const { return index[t * S + s]; }

  /// The contiguous range of tuples whose first L indices equal prefix[0 .. L).
  std::pair<int, int> range(const int* prefix, size_t L) const {
    auto below = [&](size_t t) {  // row t's prefix < prefix
      return std::lexicographical_compare(index.data() + t * S, index.data() + t * S + L, prefix, prefix + L);
    };
    auto above = [&](size_t t) {  // prefix < row t's prefix
      return std::lexicographical_compare(prefix, prefix + L, index.data() + t * S, index.data() + t * S + L);
    };
    size_t lo = 0, hi = size();
    while (lo < hi) {  // first row not below
      const size_t mid = (lo + hi) / 2;
      if (below(mid)) lo = mid + 1;
      else hi = mid;
    }
    size_t end = lo, top = size();
    while (end < top) {  // first row above
      const size_t mid = (end + top) / 2;
      if (above(mid)) top = mid;
      else end = mid + 1;
    }
    return {static_cast<int>(lo), static_cast<int>(end)};
  }
};

struct ComponentResult {
  std::vector<int> chosen;  // positions in the component's group
  double ub = 0, lb = 0;
  int iterations = 0;
  std::vector<std::vector<double>> u;  // the relaxation's multipliers at its best lower bound
  bool proven = false;                 // lb == ub proven by an exact method
};

// Two sensors: an exact 2-D assignment (a tuple with one detection is that detection's cost of staying unpaired).
ComponentResult solve_two_sensors(const RelaxationProblem& P) {
  ComponentResult r;
  std::vector<double> row_missed(static_cast<size_t>(P.n[0]), 0.0), column_missed(static_cast<size_t>(P.n[1]), 0.0);
  std::vector<int> row_tuple(row_missed.size(), -1), column_tuple(column_missed.size(), -1), pair_tuple;
  std::vector<PairCost> pairs;
  for (size_t t = 0; t < P.size(); ++t) {
    const int a = P.at(t, 0) - 1, b = P.at(t, 1) - 1;
    if (a >= 0 && b >= 0) pairs.push_back({a, b, P.cost[t]}), pair_tuple.push_back(static_cast<int>(t));
    else if (a >= 0 && P.cost[t] < row_missed[static_cast<size_t>(a)]) row_missed[static_cast<size_t>(a)] = P.cost[t], row_tuple[static_cast<size_t>(a)] = static_cast<int>(t);
    else if (b >= 0 && P.cost[t] < column_missed[static_cast<size_t>(b)]) column_missed[static_cast<size_t>(b)] = P.cost[t], column_tuple[static_cast<size_t>(b)] = static_cast<int>(t);
  }
  const auto a = assign_with_missed(row_missed, column_missed, pairs);
  std::vector<int> chosen;
  for (size_t i = 0; i < pairs.size(); ++i)
    if (a.column_of_row[static_cast<size_t>(pairs[i].row)] == pairs[i].column) chosen.push_back(pair_tuple[i]);
  for (size_t k = 0; k < row_tuple.size(); ++k)
    if (a.column_of_row[k] < 0 && row_tuple[k] >= 0) chosen.push_back(row_tuple[k]);
  for (size_t k = 0; k < column_tuple.size(); ++k)
    if (a.row_of_column[k] < 0 && column_tuple[k] >= 0) chosen.push_back(column_tuple[k]);
  for (int t : chosen) r.chosen.push_back(P.original[static_cast<size_t>(t)]), r.ub += P.cost[static_cast<size_t>(t)];
  r.lb = r.ub;
  return r;
}

// Feasible solution from the relaxed (1, 2) assignment: each further sensor added by a 2-D assignment of the
// partial tuples against its detections, the cost of extending a partial tuple by detection k being the best
// reduced cost (later sensors' multipliers) of a tuple with that prefix and index; 0 for leaving it as it is.
// The buffers are kept from one call to the next (the relaxation recovers once per iteration).
class Recovery {
 public:
  explicit Recovery(const RelaxationProblem& P) : P_(P) {}

  /// The recovered tuples (sorted positions in P), into `chosen`.
  void recover(const std::vector<std::vector<double>>& u, const MissedAssignment& relaxed, std::vector<int>& chosen) {
    const size_t S = P_.sensors();
    partial_.clear();  // partial tuples, S entries each (the later ones 0 until assigned)
    auto start = [&](size_t s, int k) {
      partial_.resize(partial_.size() + S, 0);
      partial_[partial_.size() - S + s] = k;
    };
    for (int a = 0; a < P_.n[0]; ++a) start(0, a + 1), partial_[partial_.size() - S + 1] = relaxed.column_of_row[static_cast<size_t>(a)] + 1;
    for (int b = 0; b < P_.n[1]; ++b)
      if (relaxed.row_of_column[static_cast<size_t>(b)] < 0) start(1, b + 1);
    for (size_t s = 2; s < S; ++s) {
      const size_t rows = partial_.size() / S;
      pairs_.clear();
      row_missed_.assign(rows, 0.0);
      for (size_t p = 0; p < rows; ++p) {
        const auto [lo, hi] = P_.range(partial_.data() + p * S, s);
        for (int t = lo; t < hi;) {  // tuples of the range grouped by their index at sensor s (sorted)
          const int k = P_.at(static_cast<size_t>(t), s);
          double best = kInf;
          for (; t < hi && P_.at(static_cast<size_t>(t), s) == k; ++t) {
            double r = P_.cost[static_cast<size_t>(t)];
            for (size_t q = s + 1; q < S; ++q) r -= u[q][static_cast<size_t>(P_.at(static_cast<size_t>(t), q))];
            best = std::min(best, r);
          }
          if (k == 0) row_missed_[p] = std::min(0.0, best);
          else pairs_.push_back({static_cast<int>(p), k - 1, best});
        }
      }
      column_missed_.assign(static_cast<size_t>(P_.n[s]), 0.0);
      const auto& a = solver_.solve(row_missed_, column_missed_, pairs_);
      for (size_t p = 0; p < rows; ++p) partial_[p * S + s] = a.column_of_row[p] + 1;
      for (int k = 0; k < P_.n[s]; ++k)
        if (a.row_of_column[static_cast<size_t>(k)] < 0) start(s, k + 1);
    }
    chosen.clear();
    for (size_t p = 0; p < partial_.size() / S; ++p) {
      const auto [lo, hi] = P_.range(partial_.data() + p * S, S);
      if (hi > lo) chosen.push_back(lo);
    }
    std::sort(chosen.begin(), chosen.end());
  }

 private:
  const RelaxationProblem& P_;
  std::vector<int> partial_;
  std::vector<PairCost> pairs_;
  std::vector<double> row_missed_, column_missed_;
  MissedAssignmentSolver solver_;
};

// First multipliers: each detection of a relaxed sensor gets the smallest equal share c_t / m_t of the tuples
// holding it (m_t = the tuple's detections; 0 when every such tuple costs >= 0).  These shares are a feasible
// point of the packing LP's dual (each tuple's shares sum to at most its cost), so the first lower bound is at
// least their sum, and on the passive scans it starts the subgradient far closer to the optimum than u = 0 (half
// the iterations on the coplanar grid; RESULTS, session 4).
void equal_share_multipliers(const RelaxationProblem& P, std::vector<std::vector<double>>& u) {
  const size_t S = P.sensors();
  for (size_t t = 0; t < P.size(); ++t) {
    int m = 0;
    for (size_t s = 0; s < S; ++s) m += P.at(t, s) > 0;
    const double share = P.cost[t] / m;
    for (size_t s = 2; s < S; ++s) {
      const int k = P.at(t, s);
      if (k > 0) u[s][static_cast<size_t>(k)] = std::min(u[s][static_cast<size_t>(k)], share);
    }
  }
}

ComponentResult solve_relaxation(const RelaxationProblem& P, int max_iterations, double gap_tolerance) {
  const size_t S = P.sensors(), T = P.size();
  const int n1 = P.n[0], n2 = P.n[1];
  ComponentResult out;
  // Groups of tuples with the same (i1, i2), contiguous in the sorted order.
  struct Group { int a, b, lo, hi; };
  std::vector<Group> groups;
  for (int t = 0; t < static_cast<int>(T);) {
    const int a = P.at(static_cast<size_t>(t), 0), b = P.at(static_cast<size_t>(t), 1);
    const int lo = t;
    while (t < static_cast<int>(T) && P.at(static_cast<size_t>(t), 0) == a && P.at(static_cast<size_t>(t), 1) == b) ++t;
    groups.push_back({a, b, lo, t});
  }
  std::vector<std::vector<double>> u(S), g(S);
  for (size_t s = 0; s < S; ++s) u[s].assign(static_cast<size_t>(P.n[s]) + 1, 0.0), g[s].resize(u[s].size());
  equal_share_multipliers(P, u);
  double best_ub = 0, best_lb = -kInf, factor = 1;
  int stalled = 0;
  std::vector<int> best;  // empty: every detection a false alarm, cost 0
  ExchangeImprover exchange(P.packing, 4);
  std::optional<SensorReassignment> reassignment;  // built at the second promising recovery
  Recovery recovery(P);
  MissedAssignmentSolver relaxed_solver;
  std::vector<std::vector<int>> recovered;  // recoveries already improved (the same one recurs across iterations)
  std::vector<double> reduced(T), row_missed, column_missed;
  std::vector<PairCost> pairs;
  std::vector<int> pair_tuple, row_tuple, column_tuple, relaxed, pair_of_row, feasible;
  for (int it = 0; it < max_iterations; ++it) {
    out.iterations = it + 1;
    for (size_t t = 0; t < T; ++t) {
      double r = P.cost[t];
      for (size_t s = 2; s < S; ++s) r -= u[s][static_cast<size_t>(P.at(t, s))];
      reduced[t] = r;
    }
    // The relaxed 2-D problem.
    row_missed.assign(static_cast<size_t>(n1), 0.0), column_missed.assign(static_cast<size_t>(n2), 0.0);
    row_tuple.assign(static_cast<size_t>(n1), -1), column_tuple.assign(static_cast<size_t>(n2), -1);
    pairs.clear(), pair_tuple.clear(), relaxed.clear();
    double dummy_pair = 0;  // the (0, 0) entry: every negative reduced cost may be taken
    for (const auto& gr : groups) {
      int arg = gr.lo;
      for (int t = gr.lo; t < gr.hi; ++t) {
        if (reduced[static_cast<size_t>(t)] < reduced[static_cast<size_t>(arg)]) arg = t;
        if (gr.a == 0 && gr.b == 0 && reduced[static_cast<size_t>(t)] < 0) dummy_pair += reduced[static_cast<size_t>(t)], relaxed.push_back(t);
      }
      const double r = reduced[static_cast<size_t>(arg)];
      if (gr.a == 0 && gr.b == 0) continue;
      if (gr.b == 0) {
        if (r < row_missed[static_cast<size_t>(gr.a - 1)]) row_missed[static_cast<size_t>(gr.a - 1)] = r, row_tuple[static_cast<size_t>(gr.a - 1)] = arg;
      } else if (gr.a == 0) {
        if (r < column_missed[static_cast<size_t>(gr.b - 1)]) column_missed[static_cast<size_t>(gr.b - 1)] = r, column_tuple[static_cast<size_t>(gr.b - 1)] = arg;
      } else {
        pairs.push_back({gr.a - 1, gr.b - 1, r});
        pair_tuple.push_back(arg);
      }
    }
    const auto& a = relaxed_solver.solve(row_missed, column_missed, pairs);
    double lb = a.value + dummy_pair;
    for (size_t s = 2; s < S; ++s)
      for (int k = 1; k <= P.n[s]; ++k) lb += std::min(0.0, u[s][static_cast<size_t>(k)]);  // u, or 0 when the singleton (reduced cost -u) is taken
    if (lb > best_lb) stalled = 0;
    else if (++stalled >= kStallLimit) factor *= 0.5, stalled = 0;
    if (lb > best_lb) out.u = u;
    best_lb = std::max(best_lb, lb);
    // The relaxed solution's tuples.
    pair_of_row.assign(static_cast<size_t>(n1), -1);
    for (size_t i = 0; i < pairs.size(); ++i)
      if (a.column_of_row[static_cast<size_t>(pairs[i].row)] == pairs[i].column) pair_of_row[static_cast<size_t>(pairs[i].row)] = pair_tuple[i];
    for (int r = 0; r < n1; ++r) {
      if (a.column_of_row[static_cast<size_t>(r)] >= 0) relaxed.push_back(pair_of_row[static_cast<size_t>(r)]);
      else if (row_tuple[static_cast<size_t>(r)] >= 0) relaxed.push_back(row_tuple[static_cast<size_t>(r)]);
    }
    for (int k = 0; k < n2; ++k)
      if (a.row_of_column[static_cast<size_t>(k)] < 0 && column_tuple[static_cast<size_t>(k)] >= 0) relaxed.push_back(column_tuple[static_cast<size_t>(k)]);
    // Subgradient of the relaxed constraints: 1 - uses (the singleton counts as a use).
    double g2 = 0;
    bool relaxed_feasible = true;  // no relaxed detection used twice
    for (size_t s = 2; s < S; ++s) {
      for (int k = 1; k <= P.n[s]; ++k) g[s][static_cast<size_t>(k)] = u[s][static_cast<size_t>(k)] > 0 ? 0.0 : 1.0;
      for (int t : relaxed) {
        const int k = P.at(static_cast<size_t>(t), s);
        if (k > 0) g[s][static_cast<size_t>(k)] -= 1;
      }
      for (int k = 1; k <= P.n[s]; ++k) {
        g2 += g[s][static_cast<size_t>(k)] * g[s][static_cast<size_t>(k)];
        relaxed_feasible = relaxed_feasible && (u[s][static_cast<size_t>(k)] > 0 ? 0.0 : 1.0) - g[s][static_cast<size_t>(k)] <= 1;
      }
    }
    // Upper bound: recovery, then exchange improvement.
    recovery.recover(u, a, feasible);
    double ub = 0;
    for (int t : feasible) ub += P.cost[static_cast<size_t>(t)];
    // Local search on promising recoveries only (already as good as the best improved one: the first, and any
    // that ties or beats it), each distinct one once: the first by exchange moves, the later ones by re-assigning
    // one sensor at a time (sensor_reassignment.hpp; built only when needed, so a component whose gap closes at the
    // first recovery does not pay for it).  Later recoveries differ from the earlier ones mostly by detections
    // traded among the same tuples, which the re-assignment covers (several tuples at once) at a fraction of the
    // exchange's cost.  Coplanar grid: LR optimal on 299 instead of 296 of 300 at gap 0, 4.6 % fewer instructions
    // on 3 x 20 + 5; RESULTS, passive association session 5.
    if (ub <= best_ub + kPromising * std::abs(best_ub) && std::find(recovered.begin(), recovered.end(), feasible) == recovered.end()) {
      recovered.push_back(feasible);
      if (recovered.size() == 1) {
        ub = exchange.improve(feasible, 3);
      } else {
        if (!reassignment) reassignment.emplace(S, P.n, P.index, P.cost);
        ub = reassignment->improve(feasible);
      }
    }
    if (ub < best_ub) best_ub = ub, best = feasible;
    // The relaxed solution itself, when it uses no detection twice, is a feasible one; with g = 0 it is optimal
    // (its cost equals the bound), and the loop stops below.  (Before session 5 it was not taken: the 4-sensor
    // check ended 2 of 100 scans at g = 0 with the lower bound at the optimum and a worse recovery as the answer.)
    if (relaxed_feasible) {
      double c = 0;
      for (int t : relaxed) c += P.cost[static_cast<size_t>(t)];
      if (c < best_ub) best_ub = c, best = relaxed, std::sort(best.begin(), best.end());
    }
    if (best_ub - best_lb <= gap_tolerance || g2 == 0) break;
    const double step = factor * std::max(best_ub - lb, 1e-9 * std::abs(best_ub)) / g2;
    for (size_t s = 2; s < S; ++s)
      for (int k = 1; k <= P.n[s]; ++k) u[s][static_cast<size_t>(k)] += step * g[s][static_cast<size_t>(k)];
  }
  // Gap still open: a last, more thorough exchange pass over the best solution (more refill candidates, more sweeps).
  if (best_ub - best_lb > gap_tolerance) {
    ExchangeImprover thorough(P.packing, 64);
    std::vector<int> polished = best;
    const double c = thorough.improve(polished, 20);
    if (c < best_ub) best_ub = c, best = polished;
  }
  out.ub = best_ub;
  out.lb = std::min(best_lb, best_ub);
  for (int t : best) out.chosen.push_back(P.original[static_cast<size_t>(t)]);
  return out;
}

// A component of at least two tuples by the relaxation (three or more sensors; again with other sensors relaxed
// while its gap stays above the tolerance), the 2-D assignment (two sensors) or the branch and bound (one detection).
// The relaxation's lower bound at fixed multipliers u, on the sub-problem a branch and bound node leaves (the
// available tuples, the uncovered detections): the relaxed sensors' uncovered detections each add min(0, u), the
// (1, 2) pairs are a 2-D assignment over the available tuples' least reduced costs, the all-missed pair takes every
// negative reduced cost.  Valid for any u; with the relaxation's best u it is close to the packing LP's optimum,
// far tighter than the per-detection bound of packing_branch_and_bound.hpp (which relaxes sensors 1 and 2 too).
// Tuple t of P.packing is P's tuple t; detection (q, k) of P's sensor q has id offset[q] + k - 1.
class RelaxationBound {
 public:
  RelaxationBound(const RelaxationProblem& P, const std::vector<std::vector<double>>& u) : P_(P), u_(u), reduced_(P.size()) {
    const size_t S = P.sensors();
    for (int c : P.n) offset_.push_back(detections_), detections_ += c;
    for (size_t t = 0; t < P.size(); ++t) {
      double r = P.cost[t];
      for (size_t s = 2; s < S; ++s) r -= u[s][static_cast<size_t>(P.at(t, s))];
      reduced_[t] = r;
    }
    for (int t = 0; t < static_cast<int>(P.size());) {
      const int a = P.at(static_cast<size_t>(t), 0), b = P.at(static_cast<size_t>(t), 1), lo = t;
      while (t < static_cast<int>(P.size()) && P.at(static_cast<size_t>(t), 0) == a && P.at(static_cast<size_t>(t), 1) == b) ++t;
      groups_.push_back({a, b, lo, t});
    }
  }

  double operator()(const std::vector<char>& covered, const std::vector<int>& blocked) {
    double lb = 0;
    for (size_t s = 2; s < P_.sensors(); ++s)
      for (int k = 1; k <= P_.n[s]; ++k)
        if (!covered[static_cast<size_t>(offset_[s] + k - 1)]) lb += std::min(0.0, u_[s][static_cast<size_t>(k)]);
    row_missed_.assign(static_cast<size_t>(P_.n[0]), 0.0), column_missed_.assign(static_cast<size_t>(P_.n[1]), 0.0);
    pairs_.clear();
    for (const auto& g : groups_) {
      double best = kInf;
      for (int t = g.lo; t < g.hi; ++t) {
        if (blocked[static_cast<size_t>(t)]) continue;
        const double r = reduced_[static_cast<size_t>(t)];
        if (g.a == 0 && g.b == 0) lb += std::min(0.0, r);
        best = std::min(best, r);
      }
      if (best == kInf || (g.a == 0 && g.b == 0)) continue;
      if (g.b == 0) row_missed_[static_cast<size_t>(g.a - 1)] = std::min(row_missed_[static_cast<size_t>(g.a - 1)], best);
      else if (g.a == 0) column_missed_[static_cast<size_t>(g.b - 1)] = std::min(column_missed_[static_cast<size_t>(g.b - 1)], best);
      else pairs_.push_back({g.a - 1, g.b - 1, best});
    }
    return lb + solver_.solve(row_missed_, column_missed_, pairs_).value;
  }

 private:
  struct Group { int a, b, lo, hi; };
  const RelaxationProblem& P_;
  const std::vector<std::vector<double>>& u_;
  std::vector<double> reduced_;
  std::vector<int> offset_;
  int detections_ = 0;
  std::vector<Group> groups_;
  std::vector<double> row_missed_, column_missed_;
  std::vector<PairCost> pairs_;
  MissedAssignmentSolver solver_;
};

// The branch and bound on one relaxation problem from the relaxation's result `r` (its best solution as the
// incumbent, its multipliers for the stronger bound), within `max_nodes`.  Updates r.
void close_gap(const RelaxationProblem& P, ComponentResult& r, long max_nodes) {
  std::vector<int> position(P.size());  // group position -> P's tuple
  for (size_t t = 0; t < P.size(); ++t) position[static_cast<size_t>(P.original[t])] = static_cast<int>(t);
  std::vector<int> incumbent;
  for (int c : r.chosen) incumbent.push_back(position[static_cast<size_t>(c)]);
  RelaxationBound bound(P, r.u);
  const auto sol = solve_packing_exactly(P.packing, incumbent, equal_share_multipliers(P.packing), max_nodes,
                                         [&](const std::vector<char>& c, const std::vector<int>& b) { return bound(c, b); });
  if (sol.cost < r.ub) {
    r.ub = sol.cost;
    r.chosen.clear();
    for (int t : sol.chosen) r.chosen.push_back(P.original[static_cast<size_t>(t)]);
  }
  r.lb = std::max(r.lb, sol.lower_bound);
  r.proven = sol.proven;
}

// A component of at least two tuples by the relaxation (three or more sensors; again with other sensors relaxed
// while its gap stays above the tolerance, then the branch and bound within `max_nodes` while it is still open),
// the 2-D assignment (two sensors) or the branch and bound (one detection).
ComponentResult solve_component(const std::vector<Tuple>& tuples, const std::vector<int>& group, const std::vector<int>& n,
                                const TuplePacking& all, int max_iterations, double gap_tolerance, long max_nodes) {
  ComponentResult r;
  const RelaxationProblem P(tuples, group, n);
  if (P.sensors() >= 3) {
    r = solve_relaxation(P, max_iterations, gap_tolerance);
    for (size_t rotation = 1; rotation <= kExtraRotations && rotation < P.sensors() && r.ub - r.lb > gap_tolerance;
         ++rotation) {
      const auto q = solve_relaxation(RelaxationProblem(tuples, group, n, rotation), max_iterations, gap_tolerance);
      r.lb = std::max(r.lb, q.lb);  // both bound the same component from below
      r.iterations += q.iterations;
      if (q.ub < r.ub) r.ub = q.ub, r.chosen = q.chosen;
    }
    if (r.ub - r.lb > gap_tolerance && max_nodes > 0) close_gap(P, r, max_nodes);
  } else if (P.sensors() == 2) {
    r = solve_two_sensors(P);
    r.proven = true;
  } else {  // one detection, several single-detection tuples
    long nodes = 0;
    const auto sol = solve_exactly(restrict_to(all, group), {}, 1'000'000, nodes, 0);
    r.chosen = sol.chosen, r.ub = sol.cost, r.lb = sol.lower_bound, r.proven = sol.proven;
  }
  if (r.ub - r.lb <= 1e-9 * std::max(1.0, std::abs(r.ub))) r.proven = true;
  return r;
}

void add_component(SdSolution& out, const std::vector<int>& group, const std::vector<int>& chosen_in_group) {
  for (int c : chosen_in_group) out.tuples.push_back(group[static_cast<size_t>(c)]);
  ++out.components;
  out.largest_component = std::max(out.largest_component, static_cast<int>(group.size()));
}

void finish(SdSolution& out) {
  std::sort(out.tuples.begin(), out.tuples.end());
  out.lower_bound = std::min(out.lower_bound, out.cost);
  out.absolute_gap = out.cost - out.lower_bound;
  out.gap = relative_gap(out.cost, out.lower_bound);
}

}  // namespace

SdSolution solve_sd_exact(const std::vector<Tuple>& tuples, const std::vector<int>& n, long max_nodes) {
  const TuplePacking all = packing_of(tuples, n);
  SdSolution out;
  bool proven = true;
  for (const auto& group : independent_components(all)) {
    // The relaxation run to its limit for an incumbent and multipliers, then the branch and bound proves the
    // optimum (or runs out: not proven).
    const auto r = solve_component(tuples, group, n, all, kExactIterations, kExactGap, max_nodes);
    add_component(out, group, r.chosen);
    out.cost += r.ub;
    out.lower_bound += r.lb;
    proven = proven && r.proven;
  }
  out.exact = proven;
  finish(out);
  return out;
}

SdSolution solve_sd_lagrangian(const std::vector<Tuple>& tuples, const std::vector<int>& n, int max_iterations,
                               double gap_tolerance) {
  const TuplePacking all = packing_of(tuples, n);
  SdSolution out;
  for (const auto& group : independent_components(all)) {
    ComponentResult r;
    if (group.size() == 1) {  // one tuple: take it when it beats the false alarms
      if (all.cost[static_cast<size_t>(group[0])] < 0) r.chosen = {0}, r.ub = all.cost[static_cast<size_t>(group[0])];
      r.lb = r.ub;
    } else {
      // A small component is solved exactly first (k detections hold fewer than 2^k distinct tuples).
      bool solved = false;
      if (group.size() < (1u << kSmallComponentDetections)) {
        const TuplePacking sub = restrict_to(all, group);
        if (sub.detections <= kSmallComponentDetections) {
          long nodes = 0;
          const auto sol = solve_exactly(sub, {}, kSmallComponentNodes, nodes, 0);
          r.chosen = sol.chosen, r.ub = sol.cost, r.lb = sol.lower_bound, solved = sol.proven;
        }
      }
      if (!solved) r = solve_component(tuples, group, n, all, max_iterations, gap_tolerance, kFallbackNodes);
    }
    add_component(out, group, r.chosen);
    out.cost += r.ub;
    out.lower_bound += r.lb;
    out.iterations = std::max(out.iterations, r.iterations);
  }
  finish(out);
  out.exact = out.absolute_gap <= 1e-9 * std::max(1.0, std::abs(out.cost));
  return out;
}

}  // namespace sextant::assoc
