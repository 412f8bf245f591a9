#pragma once
// SE(2) and SE(3) in the binary archive (estimators/archive/binary_archive.hpp): an SE(2) as its angle and
// translation, an SE(3) as its unit quaternion and translation, restored bit for bit (not normalized again).
#include "estimators/archive/binary_archive.hpp"
#include "estimators/lie/se2.hpp"
#include "estimators/lie/se3.hpp"

namespace sextant {

inline void save(archive::ArchiveWriter& w, const SE2& x) { w(x.angle())(x.translation()); }
inline void load(archive::ArchiveReader& r, SE2& x) {
  const double angle = r.get<double>();
  const Eigen::Vector2d t = r.get<Eigen::Vector2d>();
  if (!(angle > -M_PI - 1e-12 && angle <= M_PI)) r.fail("an SE(2) angle outside (-pi, pi]");
  x = SE2(SO2(angle), t);
}

inline void save(archive::ArchiveWriter& w, const SE3& x) { w(x.rotation().quaternion())(x.translation()); }
inline void load(archive::ArchiveReader& r, SE3& x) {
  const Eigen::Quaterniond q = r.get<Eigen::Quaterniond>();
  const Eigen::Vector3d t = r.get<Eigen::Vector3d>();
  if (!(std::abs(q.norm() - 1.0) < 1e-6)) r.fail("an SE(3) rotation that is not a unit quaternion");
  x = SE3(SO3::from_unit_quaternion(q), t);
}

}  // namespace sextant
