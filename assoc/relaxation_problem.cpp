#include "assoc/relaxation_problem.hpp"

#include <algorithm>

namespace sextant::assoc {

RelaxationProblem::RelaxationProblem(const std::vector<Tuple>& tuples, const std::vector<int>& group,
                                     const std::vector<int>& detections, size_t rotation) {
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
  if (!sensors.empty())
    std::rotate(sensors.begin(), sensors.begin() + static_cast<long>(rotation % sensors.size()), sensors.end());
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

std::pair<int, int> RelaxationProblem::range(const int* prefix, size_t L, int first, int last) const {
  auto below = [&](size_t t) {  // row t's prefix < prefix
    return std::lexicographical_compare(index.data() + t * S, index.data() + t * S + L, prefix, prefix + L);
  };
  auto above = [&](size_t t) {  // prefix < row t's prefix
    return std::lexicographical_compare(prefix, prefix + L, index.data() + t * S, index.data() + t * S + L);
  };
  size_t lo = static_cast<size_t>(first), hi = last < 0 ? size() : static_cast<size_t>(last);
  const size_t window_end = hi;
  while (lo < hi) {  // first row not below
    const size_t mid = (lo + hi) / 2;
    if (below(mid))
      lo = mid + 1;
    else
      hi = mid;
  }
  size_t end = lo, top = window_end;
  while (end < top) {  // first row above
    const size_t mid = (end + top) / 2;
    if (above(mid))
      top = mid;
    else
      end = mid + 1;
  }
  return {static_cast<int>(lo), static_cast<int>(end)};
}

std::vector<RelaxationProblem::PairGroup> RelaxationProblem::pair_groups() const {
  std::vector<PairGroup> groups;
  const int T = static_cast<int>(size());
  for (int t = 0; t < T;) {
    const int a = at(static_cast<size_t>(t), 0), b = at(static_cast<size_t>(t), 1), lo = t;
    while (t < T && at(static_cast<size_t>(t), 0) == a && at(static_cast<size_t>(t), 1) == b) ++t;
    groups.push_back({a, b, lo, t});
  }
  return groups;
}

Multipliers RelaxationProblem::zero_multipliers() const {
  Multipliers u(S);
  for (size_t q = 0; q < S; ++q) u[q].assign(static_cast<size_t>(n[q]) + 1, 0.0);
  return u;
}

void RelaxationProblem::reduced_costs(const Multipliers& u, std::vector<double>& reduced) const {
  reduced.resize(size());
  for (size_t t = 0; t < size(); ++t) {
    double r = cost[t];
    for (size_t q = 2; q < S; ++q) r -= u[q][static_cast<size_t>(at(t, q))];
    reduced[t] = r;
  }
}

}  // namespace sextant::assoc
