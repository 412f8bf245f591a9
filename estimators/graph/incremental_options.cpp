#include "estimators/graph/incremental_options.hpp"

#include <cmath>
#include <sstream>

namespace sextant::graph {

namespace {

template <class T>
std::string wrong(const char* name, T value, const char* range) {
  std::ostringstream s;
  s << name << " = " << value << ": must be " << range;
  return s.str();
}

bool positive(double v) { return std::isfinite(v) && v > 0; }
bool non_negative(double v) { return std::isfinite(v) && v >= 0; }

}  // namespace

std::string invalid_option(const IncrementalOptions& o) {
  if (!positive(o.relinearize_translation))
    return wrong("relinearize_translation", o.relinearize_translation, "a positive number (m)");
  if (!positive(o.relinearize_rotation))
    return wrong("relinearize_rotation", o.relinearize_rotation, "a positive number (rad)");
  if (o.relinearization_passes < 0) return wrong("relinearization_passes", o.relinearization_passes, ">= 0");
  if (o.relinearize_skip < 1) return wrong("relinearize_skip", o.relinearize_skip, ">= 1");
  if (!(non_negative(o.update_fraction) && o.update_fraction <= 1))
    return wrong("update_fraction", o.update_fraction, "in [0, 1]");
  if (o.min_update_factors < 1) return wrong("min_update_factors", o.min_update_factors, ">= 1");
  if (o.max_update_factors < o.min_update_factors)
    return wrong("max_update_factors", o.max_update_factors, ">= min_update_factors");
  if (!positive(o.relinearize_work)) return wrong("relinearize_work", o.relinearize_work, "a positive number");
  if (o.heavy_relinearize_every < 1) return wrong("heavy_relinearize_every", o.heavy_relinearize_every, ">= 1");
  if (o.rebuild_iterations < 1) return wrong("rebuild_iterations", o.rebuild_iterations, ">= 1");
  // At 1 any fill-in would reorder at every update.
  if (!(std::isfinite(o.refill_ratio) && o.refill_ratio > 1))
    return wrong("refill_ratio", o.refill_ratio, "a number > 1");
  if (o.nested_dissection_above < 0) return wrong("nested_dissection_above", o.nested_dissection_above, ">= 0");
  if (!non_negative(o.capacity_growth)) return wrong("capacity_growth", o.capacity_growth, "a number >= 0");
  if (o.reorder_spread < 0) return wrong("reorder_spread", o.reorder_spread, ">= 0");
  if (o.reorder_spread_above < 0) return wrong("reorder_spread_above", o.reorder_spread_above, ">= 0");
  if (o.reorder_spread_nonzeros < 0) return wrong("reorder_spread_nonzeros", o.reorder_spread_nonzeros, ">= 0");
  if (o.reorder_spread_factors < 0) return wrong("reorder_spread_factors", o.reorder_spread_factors, ">= 0");
  if (!(o.reorder_slice_ms >= 0)) return wrong("reorder_slice_ms", o.reorder_slice_ms, "a number >= 0 (ms)");
  if (!non_negative(o.wildfire)) return wrong("wildfire", o.wildfire, "a number >= 0 (m or rad)");
  if (!positive(o.kernel_width)) return wrong("kernel_width", o.kernel_width, "a positive number");
  if (o.fail_factorization_at_update < 0)
    return wrong("fail_factorization_at_update", o.fail_factorization_at_update, ">= 0 (0: never)");
  return "";
}

}  // namespace sextant::graph
