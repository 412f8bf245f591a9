#pragma once
// A FusedPose in the East-North-Up tangent plane of a GNSS datum, put on the Earth (geo_pose_t): the position as
// latitude, longitude and height on the WGS84 ellipsoid (LocalTangentPlane::to_geodetic, exact), the orientation and
// the position covariance turned from the plane's ENU into the local ENU at the body (E = enu_at(p), the rotation
// taking local ENU vectors into the plane's):
//   R_local = E' R,   Sigma_local = E' R Sigma_rho R' E
// where Sigma_rho is the FusedPose's translation block (sextant's right perturbation: in the body frame, so R Sigma_rho
// R' is its covariance in the plane).
#include "daemon/engine/outputs.hpp"
#include "estimators/geodesy/local_tangent_plane.hpp"

namespace sextant::engine {

/// The GeoPose of `pose` (whose map frame is `plane`); `heading_known`: whether that frame's heading is ENU yet.
GeoPose to_geo_pose(const FusedPose& pose, const geodesy::LocalTangentPlane& plane, bool heading_known);

}  // namespace sextant::engine
