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

ExchangeImprover::ExchangeImprover(const TuplePacking& p, int refill_candidates)
    : p_(p), refill_candidates_(refill_candidates) {
  const size_t T = p.members.size(), D = static_cast<size_t>(p.detections);
  for (size_t t = 0; t < T; ++t)
    if (p.cost[t] < 0) order_.push_back(static_cast<int>(t));
  std::stable_sort(order_.begin(), order_.end(), [&](int a, int b) { return p.cost[static_cast<size_t>(a)] < p.cost[static_cast<size_t>(b)]; });
  of_detection_.resize(D);
  cheapest_.assign(D, 0.0);
  for (int t : order_)
    for (int d : p.members[static_cast<size_t>(t)]) {
      of_detection_[static_cast<size_t>(d)].push_back(t);
      cheapest_[static_cast<size_t>(d)] = std::min(cheapest_[static_cast<size_t>(d)], p.cost[static_cast<size_t>(t)]);
    }
  owner_.assign(D, -1);
  in_.assign(T, 0);
  dropped_.assign(T, -1);
  blocked_.assign(D, -1);
}

double ExchangeImprover::improve(std::vector<int>& chosen, int max_passes) {
  const auto& p = p_;
  std::fill(owner_.begin(), owner_.end(), -1);
  std::fill(in_.begin(), in_.end(), 0);
  for (int t : chosen) {
    in_[static_cast<size_t>(t)] = 1;
    for (int d : p.members[static_cast<size_t>(t)]) owner_[static_cast<size_t>(d)] = t;
  }
  std::vector<int> conflicts, freed, refill;
  for (int pass = 0; pass < max_passes; ++pass) {
    bool improved = false;
    for (int t : order_) {
      if (in_[static_cast<size_t>(t)]) continue;
      const long stamp = ++stamp_;
      conflicts.clear(), freed.clear(), refill.clear();
      double delta = p.cost[static_cast<size_t>(t)];
      for (int d : p.members[static_cast<size_t>(t)]) {
        blocked_[static_cast<size_t>(d)] = stamp;
        const int o = owner_[static_cast<size_t>(d)];
        if (o >= 0 && dropped_[static_cast<size_t>(o)] != stamp) {
          dropped_[static_cast<size_t>(o)] = stamp, conflicts.push_back(o), delta -= p.cost[static_cast<size_t>(o)];
        }
      }
      double bound = delta;  // each refill tuple holds a freed detection of its own
      for (int o : conflicts)
        for (int d : p.members[static_cast<size_t>(o)])
          if (blocked_[static_cast<size_t>(d)] != stamp) freed.push_back(d), bound += cheapest_[static_cast<size_t>(d)];
      if (!(bound < -1e-9)) continue;
      // Greedy refill of the freed detections with tuples that fit.
      for (int d : freed) {
        if (blocked_[static_cast<size_t>(d)] == stamp) continue;
        int looked = 0;
        for (int c : of_detection_[static_cast<size_t>(d)]) {
          if (++looked > refill_candidates_) break;
          if (c == t || in_[static_cast<size_t>(c)]) continue;
          bool fits = true;
          for (int m : p.members[static_cast<size_t>(c)]) {
            const int o = owner_[static_cast<size_t>(m)];
            fits = fits && blocked_[static_cast<size_t>(m)] != stamp && (o < 0 || dropped_[static_cast<size_t>(o)] == stamp);
          }
          if (!fits) continue;
          refill.push_back(c), delta += p.cost[static_cast<size_t>(c)];
          for (int m : p.members[static_cast<size_t>(c)]) blocked_[static_cast<size_t>(m)] = stamp;
          break;
        }
      }
      if (!(delta < -1e-9)) continue;
      for (int o : conflicts) {
        in_[static_cast<size_t>(o)] = 0;
        for (int d : p.members[static_cast<size_t>(o)]) owner_[static_cast<size_t>(d)] = -1;
      }
      refill.push_back(t);
      for (int c : refill) {
        in_[static_cast<size_t>(c)] = 1;
        for (int d : p.members[static_cast<size_t>(c)]) owner_[static_cast<size_t>(d)] = c;
      }
      improved = true;
    }
    if (!improved) break;
  }
  chosen.clear();
  double cost = 0;
  for (size_t t = 0; t < in_.size(); ++t)
    if (in_[t]) chosen.push_back(static_cast<int>(t)), cost += p.cost[t];
  return cost;
}

double improve_by_exchange(const TuplePacking& p, std::vector<int>& chosen, int max_passes) {
  return ExchangeImprover(p).improve(chosen, max_passes);
}

}  // namespace sextant::assoc
