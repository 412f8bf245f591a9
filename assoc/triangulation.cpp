#include "assoc/triangulation.hpp"

#include "assoc/bearing_model.hpp"

#include <Eigen/Eigenvalues>

#include <cmath>

namespace sextant::assoc {
namespace {

double wrap(double a) {
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
  const Eigen::Index m = static_cast<Eigen::Index>(obs.size());
  Eigen::MatrixXd H(2 * m, 3);
  Eigen::VectorXd Y(2 * m);
  for (Eigen::Index s = 0; s < m; ++s) {
    const auto& o = obs[static_cast<size_t>(s)];
    const double sa = std::sin(o.azimuth), ca = std::cos(o.azimuth), se = std::sin(o.elevation), ce = std::cos(o.elevation);
    H.row(2 * s) << sa, -ca, 0;
    H.row(2 * s + 1) << ca * se, sa * se, -ce;
    Y[2 * s] = H.row(2 * s).dot(o.sensor);
    Y[2 * s + 1] = H.row(2 * s + 1).dot(o.sensor);
  }
  const Eigen::Matrix3d N = H.transpose() * H;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(N, Eigen::EigenvaluesOnly);
  t.condition = eig.eigenvalues().maxCoeff() / std::max(eig.eigenvalues().minCoeff(), 1e-300);
  if (!(eig.eigenvalues().minCoeff() > 1e-12 * eig.eigenvalues().maxCoeff())) {
    t.reason = "ill-conditioned geometry (lines of sight nearly parallel)";
    return t;
  }
  t.position = N.ldlt().solve(H.transpose() * Y);
  t.valid = t.position.allFinite();
  if (!t.valid) t.reason = "non-finite solution";
  return t;
}

Triangulation triangulate(const std::vector<BearingObservation>& obs, int steps, double max_condition) {
  Triangulation t = triangulate_linear(obs);
  if (!t.valid) return t;
  Eigen::Vector3d x = t.position;
  Eigen::Matrix3d info;
  for (int it = 0; it <= steps; ++it) {
    info.setZero();
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    double cost = 0;
    for (const auto& o : obs) {
      Eigen::Matrix<double, 2, 3> J;
      const auto h = bearing(o.sensor, x, &J);
      if (!h) {
        t.valid = false;
        t.reason = "target on a sensor's vertical (azimuth undefined)";
        return t;
      }
      const Eigen::Vector2d nu(wrap(o.azimuth - (*h)[0]), o.elevation - (*h)[1]);
      const Eigen::Matrix2d Ri = o.covariance.inverse();
      info += J.transpose() * Ri * J;
      g += J.transpose() * Ri * nu;
      cost += nu.dot(Ri * nu);
    }
    t.residual = cost;
    if (it == steps) break;
    const Eigen::Vector3d dx = info.ldlt().solve(g);
    if (!dx.allFinite()) break;
    x += dx;
    if (dx.norm() < 1e-12 * std::max(1.0, x.norm())) {
      steps = it + 1;  // converged: one more pass for the covariance and residual at x
    }
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(info, Eigen::EigenvaluesOnly);
  t.condition = eig.eigenvalues().maxCoeff() / std::max(eig.eigenvalues().minCoeff(), 1e-300);
  if (!(t.condition < max_condition)) {
    t.valid = false;
    t.reason = "ill-conditioned geometry (position not observable along one direction)";
    return t;
  }
  t.position = x;
  t.covariance = info.inverse();
  t.valid = t.position.allFinite() && t.covariance.allFinite();
  if (!t.valid) t.reason = "non-finite solution";
  return t;
}

}  // namespace sextant::assoc
