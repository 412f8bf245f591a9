#include "estimators/graph/variable.hpp"

#include <cmath>

namespace sextant::graph {

void Variable::retract(const double* d) {
  switch (kind) {
    case VariableKind::kPose2:
      pose2 = pose2 * SE2::exp(Eigen::Vector3d(d[0], d[1], d[2]));
      break;
    case VariableKind::kPose3:
      pose3 = pose3 * SE3::exp(Eigen::Map<const Vector6d>(d));
      break;
    case VariableKind::kPoint2:
      point.x() += d[0], point.y() += d[1];
      break;
    case VariableKind::kPoint3:
    case VariableKind::kVector3:
      point += Eigen::Vector3d(d[0], d[1], d[2]);
      break;
  }
}

bool Variable::finite() const {
  switch (kind) {
    case VariableKind::kPose2:
      return std::isfinite(pose2.angle()) && pose2.translation().allFinite();
    case VariableKind::kPose3:
      return pose3.translation().allFinite() && pose3.rotation().quaternion().coeffs().allFinite();
    default:
      return point.allFinite();
  }
}

}  // namespace sextant::graph
