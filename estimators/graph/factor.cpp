#include "estimators/graph/factor.hpp"

#include <array>
#include <cmath>

namespace sextant::graph {
namespace {

// g2o's toVector of a relative pose E and its derivative with respect to E's right perturbation.
void to_vector_2d(const SE2& E, double* e, Eigen::Matrix3d* D) {
  e[0] = E.translation().x();
  e[1] = E.translation().y();
  e[2] = wrap_angle(E.angle());
  if (D) {
    D->setIdentity();
    D->topLeftCorner<2, 2>() = E.rotation().matrix();
  }
}

void to_vector_3d(const SE3& E, double* e, Matrix6d* D) {
  Eigen::Quaterniond q = E.rotation().quaternion().normalized();
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  Eigen::Map<Eigen::Matrix<double, 6, 1>> v(e);
  v << E.translation(), q.vec();
  if (D) {
    D->setZero();
    D->topLeftCorner<3, 3>() = E.rotation().matrix();
    D->bottomRightCorner<3, 3>() = 0.5 * (q.w() * Eigen::Matrix3d::Identity() + SO3::hat(q.vec()));
  }
}

}  // namespace

Linearization Factor::make_linearization(const std::vector<Variable>& vars) const {
  Linearization l;
  shape(l, vars);
  return l;
}

void Factor::shape(Linearization& l, const std::vector<Variable>& vars) const {
  l.error.resize(residual_dim());  // Eigen keeps the buffer when the size is the same
  l.jacobians.resize(variables_.size());
  for (size_t k = 0; k < variables_.size(); ++k)
    l.jacobians[k].resize(residual_dim(), vars[static_cast<size_t>(variables_[k])].dim());
}

double Factor::chi2(const std::vector<Variable>& vars) const {
  Eigen::VectorXd e, weighted;
  return chi2(vars, e, weighted);
}

double Factor::chi2(const std::vector<Variable>& vars, Eigen::VectorXd& e, Eigen::VectorXd& weighted) const {
  e.resize(residual_dim());
  error(vars, e);
  return weighted_square(e, weighted);
}

RelativePoseFactor::RelativePoseFactor(int i, int j, const SE2& z, Eigen::Matrix3d information)
    : Factor({i, j}, std::move(information)), planar_(true), z2_(z) {}
RelativePoseFactor::RelativePoseFactor(int i, int j, const SE3& z, Matrix6d information)
    : Factor({i, j}, std::move(information)), planar_(false), z3_(z) {}

void RelativePoseFactor::error(const std::vector<Variable>& vars, Eigen::VectorXd& e) const {
  const auto& a = vars[static_cast<size_t>(variables()[0])];
  const auto& b = vars[static_cast<size_t>(variables()[1])];
  if (planar_)
    to_vector_2d(z2_.inverse() * (a.pose2.inverse() * b.pose2), e.data(), nullptr);
  else
    to_vector_3d(z3_.inverse() * (a.pose3.inverse() * b.pose3), e.data(), nullptr);
}

void RelativePoseFactor::linearize(const std::vector<Variable>& vars, Linearization& out) const {
  const auto& a = vars[static_cast<size_t>(variables()[0])];
  const auto& b = vars[static_cast<size_t>(variables()[1])];
  if (planar_) {
    const SE2 D = a.pose2.inverse() * b.pose2;
    Eigen::Matrix3d d;
    to_vector_2d(z2_.inverse() * D, out.error.data(), &d);
    out.jacobians[1] = d;
    out.jacobians[0] = -d * D.inverse().adjoint();
  } else {
    const SE3 D = a.pose3.inverse() * b.pose3;
    Matrix6d d;
    to_vector_3d(z3_.inverse() * D, out.error.data(), &d);
    out.jacobians[1] = d;
    out.jacobians[0] = -d * D.inverse().adjoint();
  }
}

PosePriorFactor::PosePriorFactor(int i, const SE2& z, Eigen::Matrix3d information)
    : Factor({i}, std::move(information)), planar_(true), z2_(z) {}
PosePriorFactor::PosePriorFactor(int i, const SE3& z, Matrix6d information)
    : Factor({i}, std::move(information)), planar_(false), z3_(z) {}

void PosePriorFactor::error(const std::vector<Variable>& vars, Eigen::VectorXd& e) const {
  const auto& x = vars[static_cast<size_t>(variables()[0])];
  if (planar_)
    to_vector_2d(z2_.inverse() * x.pose2, e.data(), nullptr);
  else
    to_vector_3d(z3_.inverse() * x.pose3, e.data(), nullptr);
}

void PosePriorFactor::linearize(const std::vector<Variable>& vars, Linearization& out) const {
  const auto& x = vars[static_cast<size_t>(variables()[0])];
  if (planar_) {
    Eigen::Matrix3d d;
    to_vector_2d(z2_.inverse() * x.pose2, out.error.data(), &d);
    out.jacobians[0] = d;
  } else {
    Matrix6d d;
    to_vector_3d(z3_.inverse() * x.pose3, out.error.data(), &d);
    out.jacobians[0] = d;
  }
}

PointObservationFactor::PointObservationFactor(int pose, int point, Model model, Eigen::VectorXd z,
                                               Eigen::MatrixXd information, SE3 sensor_offset)
    : Factor({pose, point}, std::move(information)),
      model_(model),
      z_(std::move(z)),
      offset_(sensor_offset),
      offset2_(SE2::from_se3(offset_)) {}

std::string PointObservationFactor::type() const {
  switch (model_) {
    case Model::kPosition:
      return "point_position";
    case Model::kRangeBearing:
      return "range_bearing";
    case Model::kRangeAzimuthElevation:
      return "range_azimuth_elevation";
    case Model::kBearing:
      return "bearing";
  }
  return "point";
}

void PointObservationFactor::error(const std::vector<Variable>& vars, Eigen::VectorXd& e) const {
  evaluate(vars, e, nullptr);
}

void PointObservationFactor::linearize(const std::vector<Variable>& vars, Linearization& out) const {
  evaluate(vars, out.error, &out);
}

namespace {
/// A sighting's Jacobian scratch, at most 3 x 6: no heap allocation per evaluation (a rebuild evaluates every one).
using SmallJacobian = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, 3, 6>;
}  // namespace

void PointObservationFactor::evaluate(const std::vector<Variable>& vars, Eigen::VectorXd& e, Linearization* out) const {
  const auto& x = vars[static_cast<size_t>(variables()[0])];
  const auto& p = vars[static_cast<size_t>(variables()[1])];
  const bool planar = x.kind == VariableKind::kPose2;
  // l = S^-1 X^-1 p, and its derivatives with respect to X's right perturbation and to p.
  Eigen::Vector3d l;
  SmallJacobian dl_dx, dl_dp;
  if (planar) {
    const SE2& s = offset2_;
    const Eigen::Vector2d l0 = x.pose2.rotation().inverse() * (p.point.head<2>() - x.pose2.translation());
    const Eigen::Vector2d ls = s.inverse().act(l0);
    l << ls, 0;
    if (out) {
      const Eigen::Matrix2d Rs = s.rotation().matrix().transpose();
      dl_dx.resize(2, 3);
      dl_dx << -Rs, Rs * Eigen::Vector2d(l0.y(), -l0.x());
      dl_dp = Rs * x.pose2.rotation().matrix().transpose();
    }
  } else {
    const Eigen::Vector3d l0 = x.pose3.inverse() * p.point;
    l = offset_.inverse() * l0;
    if (out) {
      const Eigen::Matrix3d Rs = offset_.rotation().matrix().transpose();
      dl_dx.resize(3, 6);
      dl_dx << -Rs, Rs * SO3::hat(l0);
      dl_dp = Rs * x.pose3.rotation().matrix().transpose();
    }
  }
  const int n = planar ? 2 : 3;
  // h(l) and dh/dl.
  SmallJacobian H;
  const double rxy2 = l.x() * l.x() + l.y() * l.y(), rxy = std::sqrt(rxy2);
  const double r = planar ? rxy : l.norm();
  std::array<bool, 3> angle{};  // which residual components are angles (at most 3 components)
  switch (model_) {
    case Model::kPosition:
      e = l.head(n) - z_;
      if (out) H = SmallJacobian::Identity(n, n);
      break;
    case Model::kRangeBearing:
    case Model::kRangeAzimuthElevation: {
      e.resize(residual_dim());
      e[0] = r - z_[0];
      e[1] = std::atan2(l.y(), l.x()) - z_[1];
      angle[1] = true;
      if (!planar) e[2] = std::atan2(l.z(), rxy) - z_[2], angle[2] = true;
      if (out) {
        H.setZero(residual_dim(), n);
        H.row(0) = l.head(n).transpose() / r;
        H(1, 0) = -l.y() / rxy2, H(1, 1) = l.x() / rxy2;
        if (!planar) {
          const double r2 = r * r;
          H(2, 0) = -l.x() * l.z() / (rxy * r2), H(2, 1) = -l.y() * l.z() / (rxy * r2), H(2, 2) = rxy / r2;
        }
      }
      break;
    }
    case Model::kBearing: {
      e.resize(residual_dim());
      e[0] = std::atan2(l.y(), l.x()) - z_[0];
      angle[0] = true;
      if (!planar) e[1] = std::atan2(l.z(), rxy) - z_[1], angle[1] = true;
      if (out) {
        H.setZero(residual_dim(), n);
        H(0, 0) = -l.y() / rxy2, H(0, 1) = l.x() / rxy2;
        if (!planar) {
          const double r2 = l.squaredNorm();
          H(1, 0) = -l.x() * l.z() / (rxy * r2), H(1, 1) = -l.y() * l.z() / (rxy * r2), H(1, 2) = rxy / r2;
        }
      }
      break;
    }
  }
  for (int k = 0; k < static_cast<int>(angle.size()) && k < residual_dim(); ++k)
    if (angle[static_cast<size_t>(k)]) e[k] = wrap_angle(e[k]);
  if (out) {
    out->jacobians[0] = H * dl_dx;
    out->jacobians[1] = H * dl_dp;
  }
}

PoseObservationFactor::PoseObservationFactor(int observer, int observed, PointObservationFactor::Model model,
                                             Eigen::VectorXd z, Eigen::MatrixXd information, SE3 sensor_offset,
                                             Eigen::Vector3d marker)
    : Factor({observer, observed}, information),
      point_(0, 1, model, std::move(z), std::move(information), std::move(sensor_offset)),
      marker_(std::move(marker)) {
  if (!marker_.allFinite()) throw std::invalid_argument("PoseObservationFactor: a non-finite marker position");
}

std::vector<Variable> PoseObservationFactor::observer_and_point(const std::vector<Variable>& vars) const {
  const Variable& x = vars[static_cast<size_t>(variables()[0])];
  const Variable& y = vars[static_cast<size_t>(variables()[1])];
  Variable p;
  p.kind = y.kind == VariableKind::kPose2 ? VariableKind::kPoint2 : VariableKind::kPoint3;
  if (y.kind == VariableKind::kPose2)
    p.point << y.pose2.act(marker_.head<2>()), 0;
  else
    p.point = y.pose3 * marker_;
  return {x, p};
}

void PoseObservationFactor::error(const std::vector<Variable>& vars, Eigen::VectorXd& e) const {
  point_.error(observer_and_point(vars), e);
}

void PoseObservationFactor::linearize(const std::vector<Variable>& vars, Linearization& out) const {
  const std::vector<Variable> local = observer_and_point(vars);
  Linearization point = point_.make_linearization(local);
  point_.linearize(local, point);
  const Variable& y = vars[static_cast<size_t>(variables()[1])];
  SmallJacobian dp_dy;
  if (y.kind == VariableKind::kPose2) {
    const Eigen::Matrix2d r = y.pose2.rotation().matrix();
    dp_dy.resize(2, 3);
    dp_dy << r, r * Eigen::Vector2d(-marker_.y(), marker_.x());
  } else {
    const Eigen::Matrix3d r = y.pose3.rotation().matrix();
    dp_dy.resize(3, 6);
    dp_dy << r, -r * SO3::hat(marker_);
  }
  out.error = point.error;
  out.jacobians[0] = point.jacobians[0];
  out.jacobians[1] = point.jacobians[1] * dp_dy;
}

}  // namespace sextant::graph
