#include "assoc/sensor_reassignment.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace sextant::assoc {

void SensorReassignment::sort_runs(size_t s) {
  const size_t T = cost_.size();
  auto row = [&](size_t t) { return index_.data() + t * S_; };
  auto& o = order_[s];
  // Order by (rest, index at s).  The rows are sorted lexicographically, so they already come in runs of equal
  // indices at sensors 0..s-1; only each run needs sorting, by (indices at s+1..S-1, index at s) as one
  // mixed-radix integer (or by comparing the indices when that space exceeds 64 bits).  The last sensor's order
  // is the rows' own.
  double space = n_[s] + 1.0;
  for (size_t q = s + 1; q < S_; ++q) space *= n_[q] + 1;
  const bool keyed = space < 1.8e19;
  for (size_t lo = 0; lo < T;) {
    size_t hi = lo + 1;
    while (hi < T && std::equal(row(lo), row(lo) + s, row(hi))) ++hi;
    if (hi - lo > 1) {
      if (keyed) {
        keys_.clear();
        for (size_t t = lo; t < hi; ++t) {
          const int* r = row(t);
          unsigned long long key = 0;
          for (size_t q = s + 1; q < S_; ++q)
            key = key * static_cast<unsigned long long>(n_[q] + 1) + static_cast<unsigned long long>(r[q]);
          keys_.push_back({key * static_cast<unsigned long long>(n_[s] + 1) + static_cast<unsigned long long>(r[s]),
                           static_cast<int>(t)});
        }
        std::sort(keys_.begin(), keys_.end());
        for (size_t i = lo; i < hi; ++i) o[i] = keys_[i - lo].second;
      } else {
        std::sort(o.begin() + static_cast<long>(lo), o.begin() + static_cast<long>(hi), [&](int a, int b) {
          const int* ra = row(static_cast<size_t>(a));
          const int* rb = row(static_cast<size_t>(b));
          for (size_t q = s + 1; q < S_; ++q)
            if (ra[q] != rb[q]) return ra[q] < rb[q];
          return ra[s] < rb[s];
        });
      }
    }
    lo = hi;
  }
}

SensorReassignment::SensorReassignment(size_t sensors, const std::vector<int>& n, const std::vector<int>& index,
                                       const std::vector<double>& cost)
    : S_(sensors), n_(n), index_(index), cost_(cost) {
  int total = 0;
  for (size_t s = 0; s < S_; ++s) offset_.push_back(total), total += n_[s];
  covered_.assign(static_cast<size_t>(total), 0);
  const size_t T = cost_.size();
  auto row = [&](size_t t) { return index_.data() + t * S_; };
  for (size_t t = 1; t < T; ++t)
    if (!std::lexicographical_compare(row(t - 1), row(t - 1) + S_, row(t), row(t) + S_))
      throw std::invalid_argument("SensorReassignment: tuples not sorted by their indices, or a duplicate");
  order_.resize(S_), group_begin_.resize(S_), group_of_.resize(S_), single_group_.resize(S_);
  for (size_t s = 0; s < S_; ++s) {
    auto& o = order_[s];
    o.resize(T);
    std::iota(o.begin(), o.end(), 0);
    if (s + 1 < S_) sort_runs(s);
    // Groups of equal rests.
    auto& begin = group_begin_[s];
    auto& group = group_of_[s];
    auto& single = single_group_[s];
    group.assign(T, -1), single.assign(static_cast<size_t>(total), -1);
    auto same_rest = [&](int a, int b) {
      const int* ra = index_.data() + static_cast<size_t>(a) * S_;
      const int* rb = index_.data() + static_cast<size_t>(b) * S_;
      for (size_t q = 0; q < S_; ++q)
        if (q != s && ra[q] != rb[q]) return false;
      return true;
    };
    for (size_t i = 0; i < T; ++i) {
      if (i == 0 || !same_rest(o[i - 1], o[i])) {
        begin.push_back(static_cast<int>(i));
        const int* r = index_.data() + static_cast<size_t>(o[i]) * S_;
        int held = 0, id = -1;
        for (size_t q = 0; q < S_; ++q)
          if (q != s && r[q] > 0) ++held, id = offset_[q] + r[q] - 1;
        if (held == 1) single[static_cast<size_t>(id)] = static_cast<int>(begin.size()) - 1;
      }
      group[static_cast<size_t>(o[i])] = static_cast<int>(begin.size()) - 1;
    }
    begin.push_back(static_cast<int>(T));
  }
}

bool SensorReassignment::reassign(size_t s, std::vector<int>& chosen, double& cost) {
  const size_t S = S_;
  rows_.clear();
  std::fill(covered_.begin(), covered_.end(), 0);
  for (int t : chosen) {
    rows_.push_back(group_of_[s][static_cast<size_t>(t)]);
    const int* r = index_.data() + static_cast<size_t>(t) * S;
    for (size_t q = 0; q < S; ++q)
      if (r[q] > 0) covered_[static_cast<size_t>(offset_[q] + r[q] - 1)] = 1;
  }
  // Free detections of the other sensors: rests of one detection (only those some tuple extends at sensor s).
  for (size_t q = 0; q < S; ++q) {
    if (q == s) continue;
    for (int id = offset_[q]; id < offset_[q] + n_[q]; ++id)
      if (!covered_[static_cast<size_t>(id)] && single_group_[s][static_cast<size_t>(id)] >= 0)
        rows_.push_back(single_group_[s][static_cast<size_t>(id)]);
  }
  const size_t R = rows_.size();
  row_missed_.assign(R, 0.0);
  unpaired_tuple_.assign(R, -1);
  column_missed_.assign(static_cast<size_t>(n_[s]), 0.0);
  pairs_.clear(), pair_tuple_.clear();
  const auto& o = order_[s];
  const auto& begin = group_begin_[s];
  for (size_t p = 0; p < R; ++p) {
    const auto g = static_cast<size_t>(rows_[p]);
    for (int i = begin[g]; i < begin[g + 1]; ++i) {
      const int t = o[static_cast<size_t>(i)];
      const int k = index_[static_cast<size_t>(t) * S + s];
      if (k == 0) {
        if (cost_[static_cast<size_t>(t)] < 0) row_missed_[p] = cost_[static_cast<size_t>(t)], unpaired_tuple_[p] = t;
      } else {
        pairs_.push_back({static_cast<int>(p), k - 1, cost_[static_cast<size_t>(t)]});
        pair_tuple_.push_back(t);
      }
    }
  }
  const auto& a = solver_.solve(row_missed_, column_missed_, pairs_);
  // Only a clear improvement is taken (the current solution is feasible here: value <= cost up to rounding).
  if (!(a.value < cost - 1e-9 * std::max(1.0, std::abs(cost)))) return false;
  chosen.clear();
  for (size_t i = 0; i < pairs_.size(); ++i)
    if (a.column_of_row[static_cast<size_t>(pairs_[i].row)] == pairs_[i].column) chosen.push_back(pair_tuple_[i]);
  for (size_t p = 0; p < R; ++p)
    if (a.column_of_row[p] < 0 && unpaired_tuple_[p] >= 0) chosen.push_back(unpaired_tuple_[p]);
  std::sort(chosen.begin(), chosen.end());
  cost = 0;
  for (int t : chosen) cost += cost_[static_cast<size_t>(t)];
  return true;
}

double SensorReassignment::improve(std::vector<int>& chosen, int max_rounds) {
  std::sort(chosen.begin(), chosen.end());
  double cost = 0;
  for (int t : chosen) cost += cost_[static_cast<size_t>(t)];
  // Sensor s is tried again only after another sensor's re-assignment changed the solution.
  size_t since_change = 0;
  for (int step = 0; step < max_rounds * static_cast<int>(S_) && since_change < S_; ++step) {
    if (reassign(static_cast<size_t>(step) % S_, chosen, cost))
      since_change = 1;
    else
      ++since_change;
  }
  return cost;
}

}  // namespace sextant::assoc
