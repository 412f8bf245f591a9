#include "assoc/tuple_packing.hpp"

#include <algorithm>
#include <numeric>

namespace sextant::assoc {

std::vector<std::vector<int>> independent_components(const TuplePacking& p) {
  std::vector<int> parent(static_cast<size_t>(p.detections));
  std::iota(parent.begin(), parent.end(), 0);
  auto root = [&](int x) {
    while (parent[static_cast<size_t>(x)] != x) x = parent[static_cast<size_t>(x)] = parent[static_cast<size_t>(parent[static_cast<size_t>(x)])];
    return x;
  };
  for (const auto& m : p.members)
    for (size_t i = 1; i < m.size(); ++i) parent[static_cast<size_t>(root(m[i]))] = root(m[0]);
  std::vector<int> group_of_root(static_cast<size_t>(p.detections), -1);
  std::vector<std::vector<int>> groups;
  for (size_t t = 0; t < p.members.size(); ++t) {
    if (p.members[t].empty()) {
      groups.push_back({static_cast<int>(t)});
      continue;
    }
    int& g = group_of_root[static_cast<size_t>(root(p.members[t][0]))];
    if (g < 0) g = static_cast<int>(groups.size()), groups.emplace_back();
    groups[static_cast<size_t>(g)].push_back(static_cast<int>(t));
  }
  return groups;
}

double improve_by_exchange(const TuplePacking& p, std::vector<int>& chosen, int max_passes) {
  const size_t T = p.members.size(), D = static_cast<size_t>(p.detections);
  std::vector<int> owner(D, -1);
  std::vector<char> in(T, 0);
  for (int t : chosen) {
    in[static_cast<size_t>(t)] = 1;
    for (int d : p.members[static_cast<size_t>(t)]) owner[static_cast<size_t>(d)] = t;
  }
  // Candidates, cheapest first; per detection its candidate tuples, cheapest first.
  std::vector<int> order;
  for (size_t t = 0; t < T; ++t)
    if (p.cost[t] < 0) order.push_back(static_cast<int>(t));
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return p.cost[static_cast<size_t>(a)] < p.cost[static_cast<size_t>(b)]; });
  std::vector<std::vector<int>> of_detection(D);
  for (int t : order)
    for (int d : p.members[static_cast<size_t>(t)]) of_detection[static_cast<size_t>(d)].push_back(t);
  // Stamps instead of clearing flags per move.
  std::vector<long> dropped(T, -1), blocked(D, -1);
  long stamp = 0;
  std::vector<int> conflicts, freed, refill;
  for (int pass = 0; pass < max_passes; ++pass) {
    bool improved = false;
    for (int t : order) {
      if (in[static_cast<size_t>(t)]) continue;
      ++stamp;
      conflicts.clear(), freed.clear(), refill.clear();
      double delta = p.cost[static_cast<size_t>(t)];
      for (int d : p.members[static_cast<size_t>(t)]) {
        blocked[static_cast<size_t>(d)] = stamp;
        const int o = owner[static_cast<size_t>(d)];
        if (o >= 0 && dropped[static_cast<size_t>(o)] != stamp) {
          dropped[static_cast<size_t>(o)] = stamp, conflicts.push_back(o), delta -= p.cost[static_cast<size_t>(o)];
        }
      }
      for (int o : conflicts)
        for (int d : p.members[static_cast<size_t>(o)])
          if (blocked[static_cast<size_t>(d)] != stamp) freed.push_back(d);
      // Greedy refill of the freed detections with tuples that fit.
      for (int d : freed) {
        if (blocked[static_cast<size_t>(d)] == stamp) continue;
        for (int c : of_detection[static_cast<size_t>(d)]) {
          if (c == t || in[static_cast<size_t>(c)]) continue;
          bool fits = true;
          for (int m : p.members[static_cast<size_t>(c)]) {
            const int o = owner[static_cast<size_t>(m)];
            fits = fits && blocked[static_cast<size_t>(m)] != stamp && (o < 0 || dropped[static_cast<size_t>(o)] == stamp);
          }
          if (!fits) continue;
          refill.push_back(c), delta += p.cost[static_cast<size_t>(c)];
          for (int m : p.members[static_cast<size_t>(c)]) blocked[static_cast<size_t>(m)] = stamp;
          break;
        }
      }
      if (!(delta < -1e-9)) continue;
      for (int o : conflicts) {
        in[static_cast<size_t>(o)] = 0;
        for (int d : p.members[static_cast<size_t>(o)]) owner[static_cast<size_t>(d)] = -1;
      }
      refill.push_back(t);
      for (int c : refill) {
        in[static_cast<size_t>(c)] = 1;
        for (int d : p.members[static_cast<size_t>(c)]) owner[static_cast<size_t>(d)] = c;
      }
      improved = true;
    }
    if (!improved) break;
  }
  chosen.clear();
  double cost = 0;
  for (size_t t = 0; t < T; ++t)
    if (in[t]) chosen.push_back(static_cast<int>(t)), cost += p.cost[t];
  return cost;
}

}  // namespace sextant::assoc
