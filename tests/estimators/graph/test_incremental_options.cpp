// The incremental smoother's options: the defaults are valid, each option out of its range is named with its value,
// and the smoother refuses such options at construction.
#include "estimators/graph/incremental_options.hpp"
#include "estimators/graph/incremental_smoother.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

using namespace sextant::graph;

TEST_CASE("incremental options: defaults are valid, an option out of range is named with its value") {
  CHECK(invalid_option(IncrementalOptions{}).empty());
  const double nan = std::nan(""), inf = std::numeric_limits<double>::infinity();
  struct Case {
    std::string name;
    std::function<void(IncrementalOptions&)> set;
  };
  const std::vector<Case> cases = {
      {"relinearize_translation", [](IncrementalOptions& o) { o.relinearize_translation = 0; }},
      {"relinearize_translation", [&](IncrementalOptions& o) { o.relinearize_translation = nan; }},
      {"relinearize_rotation", [](IncrementalOptions& o) { o.relinearize_rotation = -0.1; }},
      {"relinearization_passes", [](IncrementalOptions& o) { o.relinearization_passes = -1; }},
      {"relinearize_skip", [](IncrementalOptions& o) { o.relinearize_skip = 0; }},
      {"update_fraction", [](IncrementalOptions& o) { o.update_fraction = 1.5; }},
      {"min_update_factors", [](IncrementalOptions& o) { o.min_update_factors = 0; }},
      {"max_update_factors", [](IncrementalOptions& o) { o.max_update_factors = 10, o.min_update_factors = 20; }},
      {"relinearize_work", [](IncrementalOptions& o) { o.relinearize_work = 0; }},
      {"relinearize_work", [&](IncrementalOptions& o) { o.relinearize_work = nan; }},
      {"heavy_relinearize_every", [](IncrementalOptions& o) { o.heavy_relinearize_every = 0; }},
      {"rebuild_iterations", [](IncrementalOptions& o) { o.rebuild_iterations = 0; }},
      {"refill_ratio", [](IncrementalOptions& o) { o.refill_ratio = 1.0; }},
      {"refill_ratio", [&](IncrementalOptions& o) { o.refill_ratio = inf; }},
      {"nested_dissection_above", [](IncrementalOptions& o) { o.nested_dissection_above = -1; }},
      {"capacity_growth", [](IncrementalOptions& o) { o.capacity_growth = -1; }},
      {"reorder_spread", [](IncrementalOptions& o) { o.reorder_spread = -1; }},
      {"reorder_spread_above", [](IncrementalOptions& o) { o.reorder_spread_above = -1; }},
      {"reorder_spread_nonzeros", [](IncrementalOptions& o) { o.reorder_spread_nonzeros = -1; }},
      {"reorder_spread_factors", [](IncrementalOptions& o) { o.reorder_spread_factors = -1; }},
      {"reorder_slice_ms", [&](IncrementalOptions& o) { o.reorder_slice_ms = nan; }},
      {"wildfire", [](IncrementalOptions& o) { o.wildfire = -1e-3; }},
      {"kernel_width", [](IncrementalOptions& o) { o.kernel_width = 0; }},
      {"fail_factorization_at_update", [](IncrementalOptions& o) { o.fail_factorization_at_update = -1; }},
  };
  for (const Case& c : cases) {
    CAPTURE(c.name);
    IncrementalOptions o;
    c.set(o);
    const std::string why = invalid_option(o);
    CHECK(why.rfind(c.name + " = ", 0) == 0);  // the first option named is the one set out of range
    CHECK(why.find("must be") != std::string::npos);
    CHECK_THROWS_WITH_AS(IncrementalSmoother{o}, doctest::Contains(c.name.c_str()), std::invalid_argument);
  }
  // The edges of the ranges are in.
  IncrementalOptions edges;
  edges.relinearization_passes = 0, edges.update_fraction = 1.0,
  edges.min_update_factors = edges.max_update_factors = 1;
  edges.nested_dissection_above = 0, edges.capacity_growth = 0, edges.reorder_spread = 0, edges.reorder_slice_ms = inf;
  edges.wildfire = 0;
  CHECK(invalid_option(edges).empty());
}
