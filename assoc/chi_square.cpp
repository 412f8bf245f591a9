#include "assoc/chi_square.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace sextant::assoc {
namespace {

constexpr double kEpsilon = std::numeric_limits<double>::epsilon();
constexpr double kTiny = std::numeric_limits<double>::min() / kEpsilon;  // Lentz's guard against a zero denominator
// Terms of the series or the continued fraction: both need O(sqrt a) near x = a, far fewer elsewhere.
int max_terms(double a) { return 100 + static_cast<int>(20 * std::sqrt(a)); }

void check_domain(double a, double x) {
  if (!(a > 0) || !std::isfinite(a))
    throw std::invalid_argument("incomplete gamma: a = " + std::to_string(a) + " is not positive and finite");
  if (!(x >= 0)) throw std::invalid_argument("incomplete gamma: x = " + std::to_string(x) + " is negative or NaN");
}

// log of x^a e^-x / Gamma(a): the common factor of the series and the continued fraction (x > 0).
double log_prefactor(double a, double x) { return a * std::log(x) - x - std::lgamma(a); }

// P(a, x) by its series (Numerical Recipes eq. 6.2.5): e^-x x^a / Gamma(a + 1) * sum_n x^n / ((a + 1)...(a + n)).
// Converges for every x, fast for x < a + 1, where the terms shrink from the start.
double series_p(double a, double x) {
  if (x == 0) return 0;
  double term = 1 / a, sum = term;
  for (int n = 1, N = max_terms(a) + static_cast<int>(x); n < N; ++n) {
    term *= x / (a + n);
    sum += term;
    if (std::abs(term) < std::abs(sum) * kEpsilon) return sum * std::exp(log_prefactor(a, x));
  }
  throw std::runtime_error("incomplete gamma: the series did not converge for a = " + std::to_string(a) +
                           ", x = " + std::to_string(x));
}

// Q(a, x) by its continued fraction (Numerical Recipes eq. 6.2.7, even part), evaluated by the modified Lentz
// method (§5.2): e^-x x^a / Gamma(a) * 1 / (x + 1 - a - 1 (1 - a) / (x + 3 - a - 2 (2 - a) / (x + 5 - a - ...))).
// Converges fast for x > a + 1.
double continued_fraction_q(double a, double x) {
  double b = x + 1 - a, c = 1 / kTiny, d = 1 / b, h = d;
  for (int i = 1, N = max_terms(a); i < N; ++i) {
    const double an = -i * (i - a);
    b += 2;
    d = an * d + b;
    if (std::abs(d) < kTiny) d = kTiny;
    c = b + an / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1) < kEpsilon) return h * std::exp(log_prefactor(a, x));
  }
  throw std::runtime_error("incomplete gamma: the continued fraction did not converge for a = " + std::to_string(a) +
                           ", x = " + std::to_string(x));
}

// Standard normal quantile (Acklam's rational approximation, |error| < 1.2e-9): the Wilson-Hilferty start.
double normal_quantile(double p) {
  static const double a[] = {-3.969683028665376e+01, 2.209460984245205e+02,  -2.759285104469687e+02,
                             1.383577518672690e+02,  -3.066479806614716e+01, 2.506628277459239e+00};
  static const double b[] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02,
                             6.680131188771972e+01, -1.328068155288572e+01};
  static const double c[] = {-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00,
                             -2.549732539343734e+00, 4.374664141464968e+00,  2.938163982698783e+00};
  static const double d[] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00,
                             3.754408661907416e+00};
  if (p < 0.02425) {
    const double q = std::sqrt(-2 * std::log(p));
    return (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
           ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
  }
  if (p > 1 - 0.02425) return -normal_quantile(1 - p);
  const double q = p - 0.5, r = q * q;
  return (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
         (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1);
}

// A first x (gamma units) with P(a, x) near p; q = 1 - p.  a < 1: P(a, x) ~ x^a / Gamma(a + 1) ... inverted on
// [0, 1], an exponential tail beyond (Numerical Recipes §6.2.1); a >= 1: Wilson-Hilferty (Abramowitz & Stegun
// 26.4.17), or the small-x form of the series where Wilson-Hilferty's cube goes negative.
double initial_guess(double a, double p, double q) {
  if (a < 1) {
    const double t = 1 - a * (0.253 + a * 0.12);
    return p < t ? std::pow(p / t, 1 / a) : 1 - std::log(q / (1 - t));
  }
  const double k = 2 * a, s = 2 / (9 * k);
  const double w = 1 - s + normal_quantile(p) * std::sqrt(s);
  if (w > 0) return 0.5 * k * w * w * w;
  return std::exp((std::log(p) + std::lgamma(a + 1)) / a);
}

}  // namespace

double regularized_gamma_p(double a, double x) {
  check_domain(a, x);
  if (x == 0) return 0;
  if (std::isinf(x)) return 1;
  return x < a + 1 ? series_p(a, x) : 1 - continued_fraction_q(a, x);
}

double regularized_gamma_q(double a, double x) {
  check_domain(a, x);
  if (x == 0) return 1;
  if (std::isinf(x)) return 0;
  return x < a + 1 ? 1 - series_p(a, x) : continued_fraction_q(a, x);
}

double chi2_cdf(int dof, double x) {
  if (dof < 1) throw std::invalid_argument("chi2_cdf: dof = " + std::to_string(dof) + " is not positive");
  if (std::isnan(x)) throw std::invalid_argument("chi2_cdf: x is NaN");
  return x <= 0 ? 0 : regularized_gamma_p(0.5 * dof, 0.5 * x);
}

double chi2_quantile(int dof, double probability) {
  if (dof < 1) throw std::invalid_argument("chi2_quantile: dof = " + std::to_string(dof) + " is not positive");
  if (!(probability >= 0 && probability < 1))
    throw std::invalid_argument("chi2_quantile: probability " + std::to_string(probability) + " is outside [0, 1)");
  if (probability == 0) return 0;
  const double a = 0.5 * dof, p = probability, q = 1 - p;  // q exact for p >= 1/2 (Sterbenz)
  const bool upper = p > 0.5;  // solve Q(a, x) = q: near p = 1, q carries the precision p lacks
  double x = std::max(initial_guess(a, p, q), std::numeric_limits<double>::min());
  // Halley's method on f(x) = P(a, x) - p, or q - Q(a, x) (the same derivative): f' = x^(a-1) e^-x / Gamma(a),
  // f'' / f' = (a - 1) / x - 1 (Numerical Recipes §6.2.1; the curvature term capped so a step cannot reverse).
  for (int it = 0; it < 100; ++it) {
    const double f = upper ? q - regularized_gamma_q(a, x) : regularized_gamma_p(a, x) - p;
    const double df = std::exp((a - 1) * std::log(x) - x - std::lgamma(a));
    if (df == 0) break;  // underflow far out in a tail: x is as close as doubles resolve
    const double t = f / df;
    const double u = t / (1 - 0.5 * std::min(1.0, t * ((a - 1) / x - 1)));
    const double next = x - u;
    x = next > 0 ? next : 0.5 * x;  // never leave the domain: halve towards 0 instead
    if (std::abs(u) <= 1e-14 * x) break;
  }
  return 2 * x;
}

}  // namespace sextant::assoc
