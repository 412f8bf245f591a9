#include "assoc/tuple_costs.hpp"

#include "assoc/bearing_model.hpp"
#include "assoc/gaussian_divergence.hpp"
#include "assoc/chi_square.hpp"

#include <Eigen/LU>

#include <cmath>
#include <limits>
#include <stdexcept>

namespace sextant::assoc {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

double wrap(double a) {
  a = std::remainder(a, 2 * M_PI);
  return a <= -M_PI ? a + 2 * M_PI : a;
}

std::vector<BearingObservation> observations_of(const Scan& scan, const std::vector<int>& index, size_t upto) {
  std::vector<BearingObservation> obs;
  for (size_t s = 0; s < upto; ++s) {
    if (index[s] == 0) continue;
    const auto& d = scan.detections[s][static_cast<size_t>(index[s] - 1)];
    obs.push_back({scan.sensors[s], d.azimuth, d.elevation,
                   Eigen::Vector2d(d.sigma_azimuth * d.sigma_azimuth, d.sigma_elevation * d.sigma_elevation).asDiagonal()});
  }
  return obs;
}

bool passes_gate(const Triangulation& t, size_t m, double probability) {
  if (!t.valid) return false;
  const int dof = static_cast<int>(2 * m) - 3;
  return t.residual <= chi2_quantile(std::max(dof, 1), probability);
}

}  // namespace

CostKind cost_kind_from_string(const std::string& s) {
  if (s == "classic") return CostKind::kClassic;
  if (s == "kl") return CostKind::kKl;
  if (s == "renyi") return CostKind::kRenyi;
  throw std::invalid_argument("unknown cost '" + s + "' (classic, kl or renyi)");
}

double tuple_cost(const Scan& scan, const std::vector<int>& index, const CostOptions& o, Triangulation* out) {
  const auto obs = observations_of(scan, index, index.size());
  if (obs.size() < 2) return kInf;
  const Triangulation t = triangulate(obs, 2);
  if (!passes_gate(t, obs.size(), o.gate_probability)) return kInf;
  if (out) *out = t;
  double c = 0;
  for (size_t s = 0; s < index.size(); ++s) {
    if (index[s] == 0) {
      c -= std::log(1 - o.p_detect);  // +inf when P_D = 1: every sensor must take part
      continue;
    }
    const auto& d = scan.detections[s][static_cast<size_t>(index[s] - 1)];
    const Eigen::Matrix2d R = Eigen::Vector2d(d.sigma_azimuth * d.sigma_azimuth, d.sigma_elevation * d.sigma_elevation).asDiagonal();
    Eigen::Matrix<double, 2, 3> J;
    const auto h = bearing(scan.sensors[s], t.position, &J);
    if (!h) return kInf;
    const Eigen::Vector2d z(d.azimuth, d.elevation);
    const Eigen::Vector2d zh(d.azimuth - wrap(d.azimuth - (*h)[0]), (*h)[1]);  // h with its azimuth unwrapped next to z
    const Eigen::Vector2d nu = z - zh;
    c += -std::log(o.p_detect / (o.clutter_density * std::sqrt((2 * M_PI * R).determinant())));
    const Eigen::Matrix2d Sh = J * t.covariance * J.transpose();
    switch (o.kind) {
      case CostKind::kClassic: c += 0.5 * nu.dot(R.inverse() * nu); break;
      case CostKind::kKl: c += kl_divergence(z, R, zh, Sh); break;
      case CostKind::kRenyi: c += symmetric_renyi_divergence(z, R, zh, Sh, o.alpha) / o.alpha; break;
    }
  }
  return c;
}

std::vector<Tuple> build_tuples(const Scan& scan, const CostOptions& o) {
  const size_t S = scan.sensors.size();
  std::vector<Tuple> out;
  std::vector<int> index(S, 0);
  // Depth-first over sensors; a partial tuple with >= 2 detections must pass the gate to be extended.
  auto recurse = [&](auto&& self, size_t s, size_t real) -> void {
    if (s == S) {
      if (real < 2) return;
      Triangulation t;
      const double c = tuple_cost(scan, index, o, &t);
      if (c < 0) out.push_back({index, c, t.position, t.covariance});
      return;
    }
    for (int k = 0; k <= static_cast<int>(scan.detections[s].size()); ++k) {
      index[s] = k;
      const size_t r = real + (k > 0);
      if (k > 0 && r >= 2 && s + 1 < S) {
        const auto obs = observations_of(scan, index, s + 1);
        if (!passes_gate(triangulate(obs, 1), obs.size(), o.gate_probability)) continue;
      }
      self(self, s + 1, r);
    }
    index[s] = 0;
  };
  recurse(recurse, 0, 0);
  return out;
}

}  // namespace sextant::assoc
