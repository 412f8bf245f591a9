#pragma once
// Particle weights and low-variance (systematic) resampling (Thrun, Burgard & Fox, Probabilistic Robotics, 2005,
// Table 4.4; Doucet, de Freitas & Gordon 2001 for the role of resampling in a particle filter).
#include <vector>

namespace sextant::filter {

/// Turns log-weights into normalized weights w_i = exp(l_i - max l) / sum_j exp(l_j - max l) (in place, returned in
/// `weights`).  Non-finite log-weights get weight 0; when none is finite, the weights become uniform.
/// Returns false in that last case.
bool normalize_log_weights(const std::vector<double>& log_weights, std::vector<double>& weights);

/// The effective sample size N_eff = 1 / sum_i w_i^2 of normalized weights (N for uniform weights, 1 when one
/// particle holds all the weight).
double effective_sample_size(const std::vector<double>& weights);

/// Low-variance resampling: with one number u in [0, 1), draws `count` indices by the comb r_m = (u + m) / count,
/// m = 0..count-1, over the cumulative weights: index i is drawn floor or ceil of count * w_i times (never more,
/// never fewer), so the copies reproduce the weights with the least variance.  `weights` are normalized
/// (sum 1, non-negative).  Returns the indices in increasing order.
std::vector<int> low_variance_resample(const std::vector<double>& weights, int count, double u);

}  // namespace sextant::filter
