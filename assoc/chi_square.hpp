#pragma once
// Chi-square quantiles for gates: the Wilson-Hilferty approximation k (1 - 2/(9k) + z sqrt(2/(9k)))^3 with z the
// standard normal quantile (Acklam's rational approximation); within about 1 % for 2 or more degrees of freedom.

namespace sextant::assoc {

/// The chi-square quantile for `dof` degrees of freedom at `probability` (0 for dof <= 0).
double chi2_quantile(int dof, double probability);

}  // namespace sextant::assoc
