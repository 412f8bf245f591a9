#include "estimators/geodesy/local_tangent_plane.hpp"

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace sextant::geodesy {
namespace {

const Geodetic& checked(const Geodetic& p, const char* what) {
  if (!std::isfinite(p.latitude) || !std::isfinite(p.longitude) || !std::isfinite(p.altitude))
    throw std::invalid_argument(std::string(what) + ": latitude, longitude and altitude must be finite");
  if (std::abs(p.latitude) > 90)
    throw std::invalid_argument(std::string(what) + ": latitude " + std::to_string(p.latitude) + " outside [-90, 90]");
  if (std::abs(p.altitude) > 1e8)
    throw std::invalid_argument(std::string(what) + ": altitude " + std::to_string(p.altitude) + " m is not on Earth");
  return p;
}

}  // namespace

LocalTangentPlane::LocalTangentPlane(const Geodetic& datum)
    : datum_(checked(datum, "datum")), plane_(datum_.latitude, datum_.longitude, datum_.altitude) {}

Eigen::Vector3d LocalTangentPlane::to_enu(const Geodetic& p) const {
  Eigen::Vector3d e;
  plane_.Forward(p.latitude, p.longitude, p.altitude, e.x(), e.y(), e.z());
  return e;
}

Geodetic LocalTangentPlane::to_geodetic(const Eigen::Vector3d& enu) const {
  Geodetic p;
  plane_.Reverse(enu.x(), enu.y(), enu.z(), p.latitude, p.longitude, p.altitude);
  return p;
}

Eigen::Matrix3d LocalTangentPlane::enu_at(const Geodetic& p) const {
  // GeographicLib's M (row-major) rotates the ENU frame at p into this plane's ENU frame.
  std::vector<double> M(9);
  double x, y, z;
  plane_.Forward(p.latitude, p.longitude, p.altitude, x, y, z, M);
  Eigen::Matrix3d R;
  R << M[0], M[1], M[2], M[3], M[4], M[5], M[6], M[7], M[8];
  return R;
}

}  // namespace sextant::geodesy
