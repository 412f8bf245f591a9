#pragma once
// Robust kernels rho(s) of the squared error s = e' Omega e, applied by iteratively reweighted least squares:
// each factor's information is scaled by the weight w(s) = rho'(s) at the current estimate.
//   Huber  (delta):  rho = s for s <= d^2, 2 d sqrt(s) - d^2 beyond;  w = min(1, d / sqrt(s)).
//   Cauchy (delta):  rho = d^2 log(1 + s / d^2);                       w = 1 / (1 + s / d^2).
//   DCS    (phi):    dynamic covariance scaling (Agarwal et al., ICRA 2013): the error is scaled by
//                    k = min(1, 2 phi / (phi + s)), i.e. w = k^2; it switches off outlier loop closures.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace sextant::graph {

enum class RobustKernel { kNone, kHuber, kCauchy, kDcs };

/// The kernel spelt "none", "huber", "cauchy" or "dcs" (config key engine.graph.robust, `sextant optimize --robust`);
/// throws std::invalid_argument naming the spellings for any other name.
RobustKernel robust_kernel_from_name(const std::string& name);
const char* robust_kernel_name(RobustKernel kernel);
std::vector<std::string> robust_kernel_names();

/// IRLS weight of a factor whose squared error is `s`.
inline double robust_weight(RobustKernel k, double width, double s) {
  switch (k) {
    case RobustKernel::kNone:
      return 1.0;
    case RobustKernel::kHuber:
      return s <= width * width ? 1.0 : width / std::sqrt(s);
    case RobustKernel::kCauchy:
      return 1.0 / (1.0 + s / (width * width));
    case RobustKernel::kDcs: {
      const double scale = std::min(1.0, 2 * width / (width + s));
      return scale * scale;
    }
  }
  return 1.0;
}

/// The robust cost rho(s) (for DCS: k^2 s, the scaled squared error).
inline double robust_cost(RobustKernel k, double width, double s) {
  switch (k) {
    case RobustKernel::kNone:
      return s;
    case RobustKernel::kHuber:
      return s <= width * width ? s : 2 * width * std::sqrt(s) - width * width;
    case RobustKernel::kCauchy:
      return width * width * std::log1p(s / (width * width));
    case RobustKernel::kDcs:
      return robust_weight(k, width, s) * s;
  }
  return s;
}

}  // namespace sextant::graph
