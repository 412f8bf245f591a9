#include "assoc/triangulation.hpp"

#include <Eigen/Eigenvalues>

#include <cmath>

namespace sextant::assoc {
namespace {

// atan2(y, x) for the small angles of residuals: the Taylor series of atan(y / x) to the 11th power when
// |y / x| <= 0.05 (truncation error below 2e-17 relative, under a double's rounding), the library's atan2 otherwise.
double residual_angle(double y, double x) {
  if (x > 0 && std::abs(y) <= 0.05 * x) {
    const double t = y / x, t2 = t * t;
    return t * (1 + t2 * (-1.0 / 3 + t2 * (1.0 / 5 + t2 * (-1.0 / 7 + t2 * (1.0 / 9 + t2 * (-1.0 / 11))))));
  }
  return std::atan2(y, x);
}

}  // namespace

PreparedBearing::PreparedBearing(const BearingObservation& o, const Eigen::Matrix2d& inverse_covariance)
    : sensor(o.sensor),
      sin_azimuth(std::sin(o.azimuth)),
      cos_azimuth(std::cos(o.azimuth)),
      sin_elevation(std::sin(o.elevation)),
      cos_elevation(std::cos(o.elevation)),
      information(inverse_covariance) {
  // Step 1's two rows (the passive-association paper's eq. 9-12).
  const Eigen::Vector3d rows[2] = {{sin_azimuth, -cos_azimuth, 0},
                                   {cos_azimuth * sin_elevation, sin_azimuth * sin_elevation, -cos_elevation}};
  for (const auto& h : rows) {
    linear_information.noalias() += h * h.transpose();
    linear_rhs += h * h.dot(sensor);
  }
}

Triangulation triangulate_linear(const Eigen::Matrix3d& N, const Eigen::Vector3d& HtY) {
  Triangulation t;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(N, Eigen::EigenvaluesOnly);  // closed form for 3 x 3
  t.condition = eig.eigenvalues().maxCoeff() / std::max(eig.eigenvalues().minCoeff(), 1e-300);
  if (!(eig.eigenvalues().minCoeff() > 1e-12 * eig.eigenvalues().maxCoeff())) {
    t.reason = "ill-conditioned geometry (lines of sight nearly parallel)";
    return t;
  }
  t.position = N.ldlt().solve(HtY);
  t.valid = t.position.allFinite();
  if (!t.valid) t.reason = "non-finite solution";
  return t;
}

Triangulation triangulate_linear(const std::vector<BearingObservation>& obs) {
  if (obs.size() < 2) {
    Triangulation t;
    t.reason = "fewer than 2 sensors";
    return t;
  }
  // Normal equations accumulated observation by observation.
  Eigen::Matrix3d N = Eigen::Matrix3d::Zero();
  Eigen::Vector3d HtY = Eigen::Vector3d::Zero();
  for (const auto& o : obs) {
    const PreparedBearing p(o, Eigen::Matrix2d::Identity());
    N += p.linear_information;
    HtY += p.linear_rhs;
  }
  return triangulate_linear(N, HtY);
}

bool add_observation(NormalEquations& n, const PreparedBearing& o, const Eigen::Vector3d& x) {
  const Eigen::Vector3d d = x - o.sensor;
  const double rho2 = d.x() * d.x() + d.y() * d.y(), rho = std::sqrt(rho2), r2 = d.squaredNorm();
  if (rho < 1e-9 * std::max(1.0, std::sqrt(r2))) return false;  // as bearing(): on the sensor's vertical
  // The Jacobian's rows (bearing_model.hpp): azimuth a = (-dy, dx, 0) / rho^2, elevation
  // e = (-dx dz / rho, -dy dz / rho, rho) / r^2.  Written out rather than as Eigen products: the tuple builder
  // calls this for every partial tuple and Gauss-Newton step (the largest single item of its profile), and a's third
  // entry is 0 and J' R^-1 J is symmetric (6 entries, not 9).
  const double inv_rho2 = 1 / rho2, inv_r2 = 1 / r2, s = d.z() / rho * inv_r2;
  const double a0 = -d.y() * inv_rho2, a1 = d.x() * inv_rho2;
  const double e0 = -d.x() * s, e1 = -d.y() * s, e2 = rho * inv_r2;
  // z - h: azimuth between (cos az, sin az) and (dx, dy); elevation between (cos el, sin el) and (rho, dz).
  const double nu0 =
      residual_angle(o.sin_azimuth * d.x() - o.cos_azimuth * d.y(), o.cos_azimuth * d.x() + o.sin_azimuth * d.y());
  const double nu1 =
      residual_angle(o.sin_elevation * rho - o.cos_elevation * d.z(), o.cos_elevation * rho + o.sin_elevation * d.z());
  // J' R^-1 = [c0 c1] with R^-1 = [p q; q w]: c0 = p a + q e, c1 = q a + w e.
  const double p = o.information(0, 0), q = 0.5 * (o.information(0, 1) + o.information(1, 0)), w = o.information(1, 1);
  const double c00 = p * a0 + q * e0, c01 = p * a1 + q * e1, c02 = q * e2;
  const double c10 = q * a0 + w * e0, c11 = q * a1 + w * e1, c12 = w * e2;
  auto& I = n.information;
  const double i00 = c00 * a0 + c10 * e0, i01 = c00 * a1 + c10 * e1, i02 = c10 * e2;
  const double i11 = c01 * a1 + c11 * e1, i12 = c11 * e2, i22 = c12 * e2;
  I(0, 0) += i00, I(1, 1) += i11, I(2, 2) += i22;
  I(0, 1) += i01, I(1, 0) += i01, I(0, 2) += i02, I(2, 0) += i02, I(1, 2) += i12, I(2, 1) += i12;
  n.gradient.x() += c00 * nu0 + c10 * nu1;
  n.gradient.y() += c01 * nu0 + c11 * nu1;
  n.gradient.z() += c02 * nu0 + c12 * nu1;
  n.residual += p * nu0 * nu0 + 2 * q * nu0 * nu1 + w * nu1 * nu1;
  return true;
}

bool add_observation(NormalEquations& n, const BearingObservation& o, const Eigen::Matrix2d& Ri,
                     const Eigen::Vector3d& x) {
  return add_observation(n, PreparedBearing(o, Ri), x);
}

Triangulation triangulation_at(const Eigen::Vector3d& x, const NormalEquations& n, double max_condition) {
  Triangulation t;
  t.residual = n.residual;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(n.information, Eigen::EigenvaluesOnly);
  t.condition = eig.eigenvalues().maxCoeff() / std::max(eig.eigenvalues().minCoeff(), 1e-300);
  if (!(t.condition < max_condition)) {
    t.reason = "ill-conditioned geometry (position not observable along one direction)";
    return t;
  }
  t.position = x;
  t.covariance = n.information.inverse();
  t.valid = t.position.allFinite() && t.covariance.allFinite();
  if (!t.valid) t.reason = "non-finite solution";
  return t;
}

Triangulation triangulate(const std::vector<BearingObservation>& obs, int steps, double max_condition) {
  Triangulation t = triangulate_linear(obs);
  if (!t.valid) return t;
  Eigen::Vector3d x = t.position;
  std::vector<PreparedBearing> prepared;
  for (const auto& o : obs) prepared.emplace_back(o, o.covariance.inverse());
  NormalEquations n;
  for (int it = 0; it <= steps; ++it) {
    n = NormalEquations{};
    for (const auto& o : prepared) {
      if (!add_observation(n, o, x)) {
        t.valid = false;
        t.reason = "target on a sensor's vertical (azimuth undefined)";
        return t;
      }
    }
    if (it == steps) break;
    const Eigen::Vector3d dx = n.information.ldlt().solve(n.gradient);
    if (!dx.allFinite()) break;
    x += dx;
    if (dx.norm() < 1e-12 * std::max(1.0, x.norm())) {
      steps = it + 1;  // converged: one more pass for the covariance and residual at x
    }
  }
  return triangulation_at(x, n, max_condition);
}

}  // namespace sextant::assoc
