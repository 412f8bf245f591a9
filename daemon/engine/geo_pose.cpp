#include "daemon/engine/geo_pose.hpp"

#include "estimators/spd_matrix.hpp"

namespace sextant::engine {

GeoPose to_geo_pose(const FusedPose& pose, const geodesy::LocalTangentPlane& plane, bool heading_known) {
  GeoPose g;
  g.utime = pose.utime;
  g.source = pose.source;
  g.estimator = pose.estimator;
  g.heading_known = heading_known;
  const geodesy::Geodetic at = plane.to_geodetic(pose.pose.position);
  g.latitude = at.latitude;
  g.longitude = at.longitude;
  g.altitude = at.altitude;
  const Eigen::Matrix3d E = plane.enu_at(at);
  const Eigen::Matrix3d R = pose.pose.orientation.normalized().toRotationMatrix();
  g.orientation = Eigen::Quaterniond(E.transpose() * R).normalized();
  const Eigen::Matrix3d to_local = E.transpose() * R;
  g.position_covariance =
      symmetrized(Eigen::Matrix3d(to_local * pose.covariance.topLeftCorner<3, 3>() * to_local.transpose()));
  g.datum = {plane.datum().latitude, plane.datum().longitude, plane.datum().altitude};
  return g;
}

}  // namespace sextant::engine
