// The one percentile definition: the smallest value with at least a fraction p of the sample at or below it.
#include "daemon/runtime/nearest_rank_percentile.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <vector>

using sextant::runtime::nearest_rank_percentile;

TEST_CASE("nearest-rank percentile: the smallest value with at least p of the sample at or below it") {
  const std::vector<double> five{10, 20, 30, 40, 50};
  CHECK(nearest_rank_percentile(five, 0.0) == 10);
  CHECK(nearest_rank_percentile(five, 0.2) == 10);  // 1 of 5 at or below 10
  CHECK(nearest_rank_percentile(five, 0.21) == 20);
  CHECK(nearest_rank_percentile(five, 0.5) == 30);
  CHECK(nearest_rank_percentile(five, 0.99) == 50);
  CHECK(nearest_rank_percentile(five, 1.0) == 50);
  CHECK(nearest_rank_percentile({}, 0.5) == 0);
  // Against the definition itself on a larger sample: the count at or below the answer is >= p n, and below it < p n.
  std::vector<double> v;
  for (int i = 0; i < 997; ++i) v.push_back((i * 7919) % 1009);
  std::sort(v.begin(), v.end());
  for (double p : {0.01, 0.25, 0.5, 0.9, 0.99, 0.999}) {
    const double x = nearest_rank_percentile(v, p);
    const auto at_or_below = std::upper_bound(v.begin(), v.end(), x) - v.begin();
    const auto below = std::lower_bound(v.begin(), v.end(), x) - v.begin();
    CHECK(static_cast<double>(at_or_below) >= p * static_cast<double>(v.size()));
    CHECK(static_cast<double>(below) < p * static_cast<double>(v.size()));
  }
}

TEST_CASE("nearest-rank percentile of an unsorted sample: the sorted sample's, the sample left as it was") {
  const std::vector<double> shuffled{40, 10, 50, 30, 20};
  for (double p : {0.0, 0.2, 0.21, 0.5, 0.99, 1.0})
    CHECK(sextant::runtime::nearest_rank_percentile_of(shuffled, p) ==
          nearest_rank_percentile(std::vector<double>{10, 20, 30, 40, 50}, p));
  CHECK(sextant::runtime::nearest_rank_percentile_of({}, 0.5) == 0);
}
