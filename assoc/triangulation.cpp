#include "assoc/triangulation.hpp"

#include "assoc/bearing_model.hpp"

#include <Eigen/Eigenvalues>

#include <cmath>

namespace sextant::assoc {
namespace {

double wrap(double a) {
  if (a > -M_PI && a <= M_PI) return a;  // the usual case: a residual
  a = std::remainder(a, 2 * M_PI);
  return a <= -M_PI ? a + 2 * M_PI : a;
}

}  // namespace

Triangulation triangulate_linear(const std::vector<BearingObservation>& obs) {
  Triangulation t;
  if (obs.size() < 2) {
    t.reason = "fewer than 2 sensors";
    return t;
  }
  // Normal equations accumulated row by row (no heap allocation: this runs for every candidate tuple).
  Eigen::Matrix3d N = Eigen::Matrix3d::Zero();
  Eigen::Vector3d HtY = Eigen::Vector3d::Zero();
  for (const auto& o : obs) {
    const double sa = std::sin(o.azimuth), ca = std::cos(o.azimuth), se = std::sin(o.elevation), ce = std::cos(o.elevation);
    const Eigen::Vector3d rows[2] = {{sa, -ca, 0}, {ca * se, sa * se, -ce}};
    for (const auto& h : rows) {
      N.noalias() += h * h.transpose();
      HtY += h * h.dot(o.sensor);
    }
  }
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

bool add_observation(NormalEquations& n, const BearingObservation& o, const Eigen::Matrix2d& Ri, const Eigen::Vector3d& x) {
  Eigen::Matrix<double, 2, 3> J;
  const auto h = bearing(o.sensor, x, &J);
  if (!h) return false;
  const Eigen::Vector2d nu(wrap(o.azimuth - (*h)[0]), o.elevation - (*h)[1]);
  const Eigen::Matrix<double, 3, 2> JtRi = J.transpose() * Ri;
  n.information.noalias() += JtRi * J;
  n.gradient.noalias() += JtRi * nu;
  n.residual += nu.dot(Ri * nu);
  return true;
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
  NormalEquations n;
  for (int it = 0; it <= steps; ++it) {
    n = NormalEquations{};
    for (const auto& o : obs) {
      if (!add_observation(n, o, o.covariance.inverse(), x)) {
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
