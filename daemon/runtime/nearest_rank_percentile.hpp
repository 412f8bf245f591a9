#pragma once
// The nearest-rank percentile of a sample: the smallest value with at least a fraction p of the sample at or below
// it, element ceil(p n) of the sorted sample (1-based; p = 0 gives the minimum, p = 1 the maximum).  The one
// definition of a percentile in sextant: the daemon's status, the replay's summaries and `optimize --json` use it.
#include <algorithm>
#include <cmath>
#include <vector>

namespace sextant::runtime {

/// `sorted` ascending; 0 for an empty sample.
inline double nearest_rank_percentile(const std::vector<double>& sorted, double p) {
  if (sorted.empty()) return 0;
  const double rank = std::ceil(p * static_cast<double>(sorted.size())) - 1;
  return sorted[static_cast<size_t>(std::clamp(rank, 0.0, static_cast<double>(sorted.size() - 1)))];
}

/// The same of an unsorted sample (sorts a copy).
inline double nearest_rank_percentile_of(std::vector<double> sample, double p) {
  std::sort(sample.begin(), sample.end());
  return nearest_rank_percentile(sample, p);
}

}  // namespace sextant::runtime
