#pragma once
// A local East-North-Up (ENU) tangent plane anchored at a datum on the WGS84 ellipsoid: the frame sextant fuses GNSS
// fixes in (no UTM zones, no zone crossings, valid anywhere on Earth including the poles).
//
// Frames: the datum (lat0, lon0, h0) is the origin; x points East, y North, z Up along the ellipsoid normal at the
// datum.  A point (lat, lon, h) maps to  enu = R_ecef_to_enu (ecef(lat, lon, h) - ecef(lat0, lon0, h0))  exactly
// (no projection), so the plane is curved away from the ellipsoid: 1 km from the datum the Up of a point on the
// ellipsoid is about -7.8 cm (d^2 / 2R).  Angles in degrees (as in gnss_t), heights above the ellipsoid in metres.
// The geodesy is GeographicLib's LocalCartesian (Karney), exact to machine precision.
#include <Eigen/Core>

#include <GeographicLib/LocalCartesian.hpp>

namespace sextant::geodesy {

/// A geodetic point: latitude and longitude in degrees, height above the WGS84 ellipsoid in metres.
struct Geodetic {
  double latitude = 0, longitude = 0, altitude = 0;
};

class LocalTangentPlane {
 public:
  /// The plane at `datum`.  std::invalid_argument for a latitude outside [-90, 90], a non-finite value, or a height
  /// that is not on Earth (|h| > 1e5 km).
  explicit LocalTangentPlane(const Geodetic& datum);

  const Geodetic& datum() const { return datum_; }
  /// East-North-Up coordinates of `p` in metres.
  Eigen::Vector3d to_enu(const Geodetic& p) const;
  /// The geodetic point at `enu`.
  Geodetic to_geodetic(const Eigen::Vector3d& enu) const;
  /// Rotation taking vectors in the ENU frame at `p` into this plane's ENU frame (identity at the datum): a GNSS
  /// covariance given in the local ENU at the antenna becomes R Sigma R^T here.  It differs from identity by about
  /// the angle subtended at the Earth's centre (1.6e-4 rad per km).
  Eigen::Matrix3d enu_at(const Geodetic& p) const;

 private:
  Geodetic datum_;
  GeographicLib::LocalCartesian plane_;
};

}  // namespace sextant::geodesy
