// A FusedPose in a datum's ENU plane put on the Earth (daemon/engine/geo_pose.hpp), against an independent
// computation: WGS84's geodetic -> ECEF formula and the ENU bases written here, not GeographicLib.
#include "daemon/engine/geo_pose.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <numbers>

using namespace sextant;
using namespace sextant::engine;

namespace {

constexpr double kDeg = std::numbers::pi / 180;

Eigen::Vector3d ecef(double lat_deg, double lon_deg, double h) {
  const double a = 6378137.0, f = 1 / 298.257223563, e2 = f * (2 - f);
  const double lat = lat_deg * kDeg, lon = lon_deg * kDeg;
  const double n = a / std::sqrt(1 - e2 * std::sin(lat) * std::sin(lat));
  return {(n + h) * std::cos(lat) * std::cos(lon), (n + h) * std::cos(lat) * std::sin(lon),
          (n * (1 - e2) + h) * std::sin(lat)};
}

/// Rows: East, North, Up at (lat, lon) in ECEF.
Eigen::Matrix3d enu_basis(double lat_deg, double lon_deg) {
  const double lat = lat_deg * kDeg, lon = lon_deg * kDeg;
  Eigen::Matrix3d b;
  b << -std::sin(lon), std::cos(lon), 0, -std::sin(lat) * std::cos(lon), -std::sin(lat) * std::sin(lon), std::cos(lat),
      std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat);
  return b;
}

FusedPose pose_at(const Eigen::Vector3d& p, double yaw) {
  FusedPose f;
  f.utime = 42;
  f.source = "husky";
  f.estimator = "inertial";
  f.pose.position = p;
  f.pose.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()));
  f.covariance = Matrix6::Identity() * 1e-4;
  return f;
}

}  // namespace

TEST_CASE("to_geo_pose: the position on WGS84, orientation and covariance in the local ENU, the datum") {
  const geodesy::Geodetic datum{49.9, 8.65, 140.0};
  const geodesy::LocalTangentPlane plane(datum);
  const Eigen::Matrix3d B0 = enu_basis(datum.latitude, datum.longitude);
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(350, -120, 4),
                                   Eigen::Vector3d(10'000, 25'000, -30), Eigen::Vector3d(-80'000, 5'000, 900)}) {
    CAPTURE(p.transpose());
    FusedPose f = pose_at(p, 0.7);
    f.covariance(0, 0) = 4.0;  // 2 m along the body's x axis
    const GeoPose g = to_geo_pose(f, plane, true);
    // The geodetic point is the plane's point: ENU at the datum of its ECEF position gives p back.
    const Eigen::Vector3d back =
        B0 * (ecef(g.latitude, g.longitude, g.altitude) - ecef(datum.latitude, datum.longitude, datum.altitude));
    CHECK((back - p).norm() < 1e-6);
    // The body's x axis, seen in the local ENU at the body, is the plane's x axis carried through ECEF.
    const Eigen::Matrix3d B = enu_basis(g.latitude, g.longitude);
    const Eigen::Vector3d x_plane = f.pose.orientation * Eigen::Vector3d::UnitX();
    const Eigen::Vector3d x_local = B * B0.transpose() * x_plane;
    CHECK((g.orientation * Eigen::Vector3d::UnitX() - x_local).norm() < 1e-9);
    // 2 m of sigma along the body's x: 4 m^2 along that direction in the local ENU, 1e-4 across it.
    CHECK(x_local.dot(g.position_covariance * x_local) == doctest::Approx(4.0).epsilon(1e-9));
    const Eigen::Vector3d across = x_local.cross(B * B0.transpose() * Eigen::Vector3d::UnitZ()).normalized();
    CHECK(across.dot(g.position_covariance * across) == doctest::Approx(1e-4).epsilon(1e-6));
    CHECK(g.datum == Eigen::Vector3d(datum.latitude, datum.longitude, datum.altitude));
    CHECK(g.utime == 42);
    CHECK(g.source == "husky");
    CHECK(g.estimator == "inertial");
    CHECK(g.heading_known);
  }
  // Far from the datum the local ENU turns away from the plane's (1.6e-4 rad per km): 80 km west, about 0.72 deg.
  const GeoPose far = to_geo_pose(pose_at({-80'000, 0, 0}, 0), plane, false);
  const double turn = Eigen::AngleAxisd(far.orientation).angle();
  CHECK(turn == doctest::Approx(80 * 1.57e-4).epsilon(0.05));
  CHECK_FALSE(far.heading_known);
}
