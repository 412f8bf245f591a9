#include "estimators/filter/planar_ekf.hpp"

#include <cmath>

namespace sextant::filter {

void PlanarEkf::initialize(const SE2& pose, const Eigen::Matrix3d& covariance) {
  x_ = Eigen::VectorXd::Zero(3);
  x_ << pose.translation(), pose.angle();
  P_ = covariance;
  slot_.clear();
  initialized_ = true;
}

Eigen::Vector3d PlanarEkf::motion(const Eigen::Vector3d& x, const SE2& d, Eigen::Matrix3d* F, Eigen::Matrix3d* G) {
  const double c = std::cos(x[2]), s = std::sin(x[2]);
  const double dx = d.translation().x(), dy = d.translation().y();
  if (F) {
    *F = Eigen::Matrix3d::Identity();
    (*F)(0, 2) = -s * dx - c * dy;
    (*F)(1, 2) = c * dx - s * dy;
  }
  const double th = x[2] + d.angle();
  if (G) {
    *G = Eigen::Matrix3d::Identity();
    G->topLeftCorner<2, 2>() = SO2(th).matrix();
  }
  return {x[0] + c * dx - s * dy, x[1] + s * dx + c * dy, wrap_angle(th)};
}

Eigen::Vector2d PlanarEkf::observation(const Eigen::Vector3d& r, const Eigen::Vector2d& l, Eigen::Matrix<double, 2, 3>* Hx,
                                       Eigen::Matrix2d* Hl) {
  const Eigen::Vector2d d = l - r.head<2>();
  const double q = d.squaredNorm(), sq = std::sqrt(q);
  if (Hx) *Hx << -d.x() / sq, -d.y() / sq, 0, d.y() / q, -d.x() / q, -1;
  if (Hl) *Hl << d.x() / sq, d.y() / sq, -d.y() / q, d.x() / q;
  return {sq, wrap_angle(std::atan2(d.y(), d.x()) - r[2])};
}

void PlanarEkf::predict(const SE2& delta, const Eigen::Matrix3d& Q) {
  Eigen::Matrix3d F, G;
  x_.head<3>() = motion(x_.head<3>(), delta, &F, &G);
  const Eigen::Index n = x_.size();
  // Only the robot rows and columns change: P_rr = F P_rr F' + G Q G', P_rl = F P_rl.
  const Eigen::Matrix3d Prr = F * P_.topLeftCorner<3, 3>() * F.transpose() + G * Q * G.transpose();
  P_.topLeftCorner<3, 3>() = 0.5 * (Prr + Prr.transpose());
  if (n > 3) {
    P_.topRightCorner(3, n - 3) = F * P_.topRightCorner(3, n - 3);
    P_.bottomLeftCorner(n - 3, 3) = P_.topRightCorner(3, n - 3).transpose();
  }
}

UpdateResult PlanarEkf::observe(int64_t id, double range, double bearing, const Eigen::Matrix2d& R) {
  UpdateResult out;
  if (!std::isfinite(range) || !std::isfinite(bearing) || !R.allFinite() || range <= 0) {
    out.reason = "non_finite";
    return out;
  }
  Eigen::Vector2d z(range, bearing);
  Eigen::Matrix<double, 2, 3> Hx;
  Eigen::Matrix2d Hl;
  Eigen::Vector2d predicted;
  // H is zero but for the robot's 3 columns and the landmark's 2: P H' and H P H' in O(n).
  Eigen::MatrixXd PHt, HPHt;
  if (auto k = known_.find(id); k != known_.end()) {
    predicted = observation(x_.head<3>(), k->second, &Hx, nullptr);
    PHt = P_.leftCols<3>() * Hx.transpose();
    HPHt = Hx * PHt.topRows<3>();
  } else if (auto s = slot_.find(id); s != slot_.end()) {
    predicted = observation(x_.head<3>(), x_.segment<2>(s->second), &Hx, &Hl);
    PHt = P_.leftCols<3>() * Hx.transpose() + P_.middleCols<2>(s->second) * Hl.transpose();
    HPHt = Hx * PHt.topRows<3>() + Hl * PHt.middleRows<2>(s->second);
  } else {
    if (!options_.slam || id < 0) {
      out.reason = "unknown_landmark";
      return out;
    }
    if (static_cast<int>(slot_.size()) >= options_.max_landmarks) {
      out.reason = "map_full";
      return out;
    }
    augment(id, range, bearing, R);
    out.accepted = true;
    out.reason = "new_landmark";
    return out;
  }
  if (predicted[0] < 1e-6) {
    out.reason = "singular";
    return out;
  }
  Eigen::VectorXd r = z - predicted;
  r[1] = wrap_angle(r[1]);
  out = kalman_update_from(x_, P_, r, PHt, HPHt, R, options_.gate);
  x_[2] = wrap_angle(x_[2]);
  return out;
}

void PlanarEkf::augment(int64_t id, double range, double bearing, const Eigen::Matrix2d& R) {
  const Eigen::Index n = x_.size();
  const double a = x_[2] + bearing, c = std::cos(a), s = std::sin(a);
  const Eigen::Vector2d l(x_[0] + range * c, x_[1] + range * s);
  Eigen::Matrix<double, 2, 3> Jx;
  Jx << 1, 0, -range * s, 0, 1, range * c;
  Eigen::Matrix2d Jz;
  Jz << c, -range * s, s, range * c;
  x_.conservativeResize(n + 2);
  x_.tail<2>() = l;
  Eigen::MatrixXd P(n + 2, n + 2);
  P.topLeftCorner(n, n) = P_;
  const Eigen::MatrixXd cross = Jx * P_.topRows(3);  // 2 x n
  P.bottomLeftCorner(2, n) = cross;
  P.topRightCorner(n, 2) = cross.transpose();
  const Eigen::Matrix2d Pll = Jx * P_.topLeftCorner<3, 3>() * Jx.transpose() + Jz * R * Jz.transpose();
  P.bottomRightCorner<2, 2>() = 0.5 * (Pll + Pll.transpose());
  P_ = std::move(P);
  slot_[id] = static_cast<int>(n);
}

std::map<int64_t, Eigen::Vector2d> PlanarEkf::landmarks() const {
  std::map<int64_t, Eigen::Vector2d> out = known_;
  for (const auto& [id, k] : slot_) out[id] = x_.segment<2>(k);
  return out;
}

}  // namespace sextant::filter
