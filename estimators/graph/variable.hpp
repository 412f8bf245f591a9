#pragma once
// The variables of a factor graph: planar and spatial poses, points, and plain 3-vectors of a keyframe's state
// (a velocity in m/s, an IMU bias in rad/s or m/s^2).  Each is updated on its manifold by X <- X (+) delta (right
// perturbation for poses, addition for points and vectors); `dim` is the size of delta.
#include "estimators/lie/se2.hpp"
#include "estimators/lie/se3.hpp"

#include <cstdint>

namespace sextant::graph {

enum class VariableKind { kPose2, kPose3, kPoint2, kPoint3, kVector3 };

/// Tangent dimension of a kind: 3, 6, 2, 3, 3.
constexpr int tangent_dim(VariableKind k) {
  return k == VariableKind::kPose2 ? 3 : k == VariableKind::kPose3 ? 6 : k == VariableKind::kPoint2 ? 2 : 3;
}

struct Variable {
  int64_t id = 0;  // the user's id (g2o vertex id)
  VariableKind kind = VariableKind::kPose2;
  bool fixed = false;
  SE2 pose2;
  SE3 pose3;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  // Point2 uses x, y; Vector3 holds its vector here

  int dim() const { return tangent_dim(kind); }
  /// X <- X (+) delta.
  void retract(const double* delta);
  bool is_pose() const { return kind == VariableKind::kPose2 || kind == VariableKind::kPose3; }
  /// A landmark (a point in the map), as opposed to a pose or a vector attached to one.
  bool is_point() const { return kind == VariableKind::kPoint2 || kind == VariableKind::kPoint3; }
  /// The pose as SE(3) (planar poses embedded with z = 0).
  SE3 as_se3() const { return kind == VariableKind::kPose3 ? pose3 : pose2.to_se3(); }
  /// The pose's position (planar poses with z = 0): as_se3().translation() without forming the rotation.
  Eigen::Vector3d position() const {
    return kind == VariableKind::kPose3 ? pose3.translation()
                                        : Eigen::Vector3d(pose2.translation().x(), pose2.translation().y(), 0.0);
  }
  /// False when any coordinate is NaN or infinite.
  bool finite() const;
};

}  // namespace sextant::graph
