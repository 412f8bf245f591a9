#include "assoc/tuple_packing.hpp"

#include <algorithm>
#include <numeric>

namespace sextant::assoc {

std::vector<std::vector<int>> independent_components(const TuplePacking& p) {
  std::vector<int> parent(static_cast<size_t>(p.detections));
  std::iota(parent.begin(), parent.end(), 0);
  auto root = [&](int x) {
    while (parent[static_cast<size_t>(x)] != x)
      x = parent[static_cast<size_t>(x)] = parent[static_cast<size_t>(parent[static_cast<size_t>(x)])];
    return x;
  };
  for (size_t t = 0; t < p.size(); ++t) {
    const auto m = p.members(t);
    for (size_t i = 1; i < m.size(); ++i) parent[static_cast<size_t>(root(m[i]))] = root(m[0]);
  }
  std::vector<int> group_of_root(static_cast<size_t>(p.detections), -1);
  std::vector<std::vector<int>> groups;
  for (size_t t = 0; t < p.size(); ++t) {
    const auto m = p.members(t);
    if (m.empty()) {
      groups.push_back({static_cast<int>(t)});
      continue;
    }
    int& g = group_of_root[static_cast<size_t>(root(m[0]))];
    if (g < 0) g = static_cast<int>(groups.size()), groups.emplace_back();
    groups[static_cast<size_t>(g)].push_back(static_cast<int>(t));
  }
  return groups;
}

ExchangeImprover::ExchangeImprover(const TuplePacking& p, int refill_candidates)
    : refill_candidates_(refill_candidates) {
  const size_t T = p.size(), D = static_cast<size_t>(p.detections);
  tuple_of_rank_.resize(T);
  std::iota(tuple_of_rank_.begin(), tuple_of_rank_.end(), 0);
  std::stable_sort(tuple_of_rank_.begin(), tuple_of_rank_.end(), [&](int a, int b) {
    const double ca = p.cost[static_cast<size_t>(a)], cb = p.cost[static_cast<size_t>(b)];
    return ca < 0 && cb < 0 ? ca < cb : ca < 0 && !(cb < 0);  // negative ones cheapest first, the rest after
  });
  rank_of_tuple_.resize(T);
  member_begin_.assign(1, 0);
  for (size_t r = 0; r < T; ++r) {
    const auto t = static_cast<size_t>(tuple_of_rank_[r]);
    rank_of_tuple_[t] = static_cast<int>(r);
    cost_.push_back(p.cost[t]);
    if (p.cost[t] < 0) ++negative_;
    const auto m = p.members(t);
    members_.insert(members_.end(), m.begin(), m.end());
    member_begin_.push_back(static_cast<int>(members_.size()));
  }
  // Per detection, its negative tuples by rank (counting sort: ranks come out ascending, i.e. cheapest first).
  of_detection_begin_.assign(D + 1, 0);
  cheapest_.assign(D, 0.0);
  for (int r = 0; r < negative_; ++r)
    for (int i = member_begin_[static_cast<size_t>(r)]; i < member_begin_[static_cast<size_t>(r) + 1]; ++i) {
      const auto d = static_cast<size_t>(members_[static_cast<size_t>(i)]);
      ++of_detection_begin_[d + 1];
      cheapest_[d] = std::min(cheapest_[d], cost_[static_cast<size_t>(r)]);
    }
  for (size_t d = 0; d < D; ++d) of_detection_begin_[d + 1] += of_detection_begin_[d];
  of_detection_.resize(static_cast<size_t>(of_detection_begin_[D]));
  std::vector<int> fill(of_detection_begin_.begin(), of_detection_begin_.end() - 1);
  for (int r = 0; r < negative_; ++r)
    for (int i = member_begin_[static_cast<size_t>(r)]; i < member_begin_[static_cast<size_t>(r) + 1]; ++i)
      of_detection_[static_cast<size_t>(fill[static_cast<size_t>(members_[static_cast<size_t>(i)])]++)] = r;
  owner_.assign(D, -1);
  in_.assign(T, 0);
  look_.assign(T, 0);
  dropped_.assign(T, -1);
  blocked_.assign(D, -1);
  freed_.assign(D, -1);
  counted_.assign(D, -1);
}

double ExchangeImprover::improve(std::vector<int>& chosen, int max_passes) {
  load(chosen);
  for (int pass = 0; pass < max_passes; ++pass) {
    bool improved = false;
    for (int t = 0; t < negative_; ++t) {
      if (!look_[static_cast<size_t>(t)] || in_[static_cast<size_t>(t)]) continue;
      look_[static_cast<size_t>(t)] = 0;
      if (try_move(t)) improved = true;
    }
    if (!improved) break;
  }
  return unload(chosen);
}

// The chosen tuples in (by rank), their detections owned; every negative tuple to be looked at.
void ExchangeImprover::load(const std::vector<int>& chosen) {
  std::fill(owner_.begin(), owner_.end(), -1);
  std::fill(in_.begin(), in_.end(), 0);
  std::fill(look_.begin(), look_.begin() + negative_, 1);
  const int* mem = members_.data();
  const int* begin = member_begin_.data();
  for (int t : chosen) {
    const int r = rank_of_tuple_[static_cast<size_t>(t)];
    in_[static_cast<size_t>(r)] = 1;
    for (int i = begin[r]; i < begin[r + 1]; ++i) owner_[static_cast<size_t>(mem[i])] = r;
  }
}

// The move that puts tuple t in: the chosen tuples sharing a detection with it out, the detections they free
// refilled greedily; made when it lowers the cost.  True when made.
bool ExchangeImprover::try_move(int t) {
  const int* mem = members_.data();
  const int* begin = member_begin_.data();
  const long stamp = ++stamp_;
  conflicts_.clear(), freed_ids_.clear(), refill_.clear();
  double delta = cost_[static_cast<size_t>(t)];
  for (int i = begin[t]; i < begin[t + 1]; ++i) {
    const int d = mem[i];
    blocked_[static_cast<size_t>(d)] = stamp;
    const int o = owner_[static_cast<size_t>(d)];
    if (o >= 0 && dropped_[static_cast<size_t>(o)] != stamp) {
      dropped_[static_cast<size_t>(o)] = stamp, conflicts_.push_back(o), delta -= cost_[static_cast<size_t>(o)];
    }
  }
  double bound = delta;  // each refill tuple holds a freed detection of its own
  for (int o : conflicts_)
    for (int i = begin[o]; i < begin[o + 1]; ++i)
      if (blocked_[static_cast<size_t>(mem[i])] != stamp) {
        freed_ids_.push_back(mem[i]), bound += cheapest_[static_cast<size_t>(mem[i])];
        freed_[static_cast<size_t>(mem[i])] = stamp;
      }
  if (!(bound < -1e-9)) return false;
  delta = refill_freed(t, stamp, delta, bound);
  if (!(delta < -1e-9)) return false;
  apply_move(t);
  return true;
}

// Greedy refill of the freed detections with tuples that fit; returns the move's cost change.  `rest` bounds what
// the freed detections not yet refilled can still gain (each at most its cheapest tuple); once delta + rest cannot
// go below zero the move is rejected without looking further (the same decision as finishing the refill).
double ExchangeImprover::refill_freed(int t, long stamp, double delta, double bound) {
  const int* mem = members_.data();
  const int* begin = member_begin_.data();
  double rest = bound - delta;
  for (int d : freed_ids_) {
    if (!(delta + rest < -1e-9)) break;
    if (blocked_[static_cast<size_t>(d)] == stamp) continue;  // taken by an earlier refill tuple
    rest -= cheapest_[static_cast<size_t>(d)];
    counted_[static_cast<size_t>(d)] = stamp;
    int looked = 0;
    for (int j = of_detection_begin_[static_cast<size_t>(d)]; j < of_detection_begin_[static_cast<size_t>(d) + 1];
         ++j) {
      const int c = of_detection_[static_cast<size_t>(j)];
      if (++looked > refill_candidates_) break;
      if (c == t || in_[static_cast<size_t>(c)]) continue;
      // Fits: every detection unblocked and either free or freed by this move.
      bool fits = true;
      for (int i = begin[c]; i < begin[c + 1] && fits; ++i) {
        const auto m = static_cast<size_t>(mem[i]);
        fits = blocked_[m] != stamp && (owner_[m] < 0 || freed_[m] == stamp);
      }
      if (!fits) continue;
      refill_.push_back(c), delta += cost_[static_cast<size_t>(c)];
      for (int i = begin[c]; i < begin[c + 1]; ++i) {
        const auto m = static_cast<size_t>(mem[i]);
        if (freed_[m] == stamp && counted_[m] != stamp)
          rest -= cheapest_[m], counted_[m] = stamp;  // refilled along with d
        blocked_[m] = stamp;
      }
      break;
    }
  }
  return delta;
}

// The conflicts out, t and its refill in; every tuple holding a detection that changed hands is looked at again.
void ExchangeImprover::apply_move(int t) {
  const int* mem = members_.data();
  const int* begin = member_begin_.data();
  for (int o : conflicts_) {
    in_[static_cast<size_t>(o)] = 0;
    for (int i = begin[o]; i < begin[o + 1]; ++i) owner_[static_cast<size_t>(mem[i])] = -1, touched(mem[i]);
  }
  refill_.push_back(t);
  for (int c : refill_) {
    in_[static_cast<size_t>(c)] = 1;
    for (int i = begin[c]; i < begin[c + 1]; ++i) owner_[static_cast<size_t>(mem[i])] = c, touched(mem[i]);
  }
}

// Detection d changed hands: every tuple containing it has a new bound.
void ExchangeImprover::touched(int d) {
  for (int i = of_detection_begin_[static_cast<size_t>(d)]; i < of_detection_begin_[static_cast<size_t>(d) + 1]; ++i)
    look_[static_cast<size_t>(of_detection_[static_cast<size_t>(i)])] = 1;
}

// The chosen tuples back as sorted tuple indices; their cost.
double ExchangeImprover::unload(std::vector<int>& chosen) const {
  chosen.clear();
  for (size_t r = 0; r < in_.size(); ++r)
    if (in_[r]) chosen.push_back(tuple_of_rank_[r]);
  std::sort(chosen.begin(), chosen.end());
  double cost = 0;  // summed in tuple order, as the callers sum
  for (int t : chosen) cost += cost_[static_cast<size_t>(rank_of_tuple_[static_cast<size_t>(t)])];
  return cost;
}

double improve_by_exchange(const TuplePacking& p, std::vector<int>& chosen, int max_passes) {
  return ExchangeImprover(p).improve(chosen, max_passes);
}

}  // namespace sextant::assoc
