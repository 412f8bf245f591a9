#include "estimators/filter/low_variance_resampling.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace sextant::filter {

bool normalize_log_weights(const std::vector<double>& log_weights, std::vector<double>& weights) {
  const size_t n = log_weights.size();
  weights.assign(n, 0.0);
  double top = -std::numeric_limits<double>::infinity();
  for (double l : log_weights)
    if (std::isfinite(l)) top = std::max(top, l);
  if (!std::isfinite(top)) {
    if (n > 0) weights.assign(n, 1.0 / static_cast<double>(n));
    return false;
  }
  double sum = 0;
  for (size_t i = 0; i < n; ++i) {
    weights[i] = std::isfinite(log_weights[i]) ? std::exp(log_weights[i] - top) : 0.0;
    sum += weights[i];
  }
  for (double& w : weights) w /= sum;  // sum >= 1: the largest term is exp(0)
  return true;
}

double effective_sample_size(const std::vector<double>& weights) {
  double s = 0;
  for (double w : weights) s += w * w;
  return s > 0 ? 1.0 / s : 0.0;
}

std::vector<int> low_variance_resample(const std::vector<double>& weights, int count, double u) {
  std::vector<int> out;
  if (weights.empty() || count <= 0) return out;
  out.reserve(static_cast<size_t>(count));
  const double step = 1.0 / count;
  double r = std::clamp(u, 0.0, std::nextafter(1.0, 0.0)) * step;
  double c = weights[0];
  int i = 0;
  const int last = static_cast<int>(weights.size()) - 1;
  for (int m = 0; m < count; ++m) {
    const double target = r + m * step;
    while (c <= target && i < last) c += weights[static_cast<size_t>(++i)];  // skips zero weights
    out.push_back(i);
  }
  return out;
}

}  // namespace sextant::filter
