// The local East-North-Up plane against the textbook geodetic -> ECEF -> ENU formulas written here (WGS84), its
// round trip, the rotation between tangent planes, and the refusal of impossible datums.
#include "estimators/geodesy/local_tangent_plane.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <random>

using namespace sextant::geodesy;

namespace {

constexpr double kA = 6378137.0, kF = 1 / 298.257223563, kE2 = kF * (2 - kF);

Eigen::Vector3d ecef(const Geodetic& g) {
  const double lat = g.latitude * M_PI / 180, lon = g.longitude * M_PI / 180;
  const double N = kA / std::sqrt(1 - kE2 * std::sin(lat) * std::sin(lat));
  return {(N + g.altitude) * std::cos(lat) * std::cos(lon), (N + g.altitude) * std::cos(lat) * std::sin(lon),
          (N * (1 - kE2) + g.altitude) * std::sin(lat)};
}

// Rows: East, North, Up at g, in ECEF.
Eigen::Matrix3d ecef_to_enu(const Geodetic& g) {
  const double lat = g.latitude * M_PI / 180, lon = g.longitude * M_PI / 180;
  Eigen::Matrix3d R;
  R << -std::sin(lon), std::cos(lon), 0, -std::sin(lat) * std::cos(lon), -std::sin(lat) * std::sin(lon), std::cos(lat),
      std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat);
  return R;
}

}  // namespace

TEST_CASE("local tangent plane: ENU against the ECEF formulas, round trip, and rotation between planes") {
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> lat(-89, 89), lon(-180, 180), d(-0.05, 0.05), h(-50, 500);
  for (int trial = 0; trial < 50; ++trial) {
    const Geodetic datum{lat(rng), lon(rng), h(rng)};
    const LocalTangentPlane plane(datum);
    CHECK(plane.to_enu(datum).norm() < 1e-9);
    for (int k = 0; k < 10; ++k) {
      const Geodetic p{datum.latitude + d(rng), datum.longitude + d(rng), h(rng)};  // within a few km
      const Eigen::Vector3d expected = ecef_to_enu(datum) * (ecef(p) - ecef(datum));
      const Eigen::Vector3d enu = plane.to_enu(p);
      CHECK((enu - expected).norm() < 1e-6);
      const Geodetic back = plane.to_geodetic(enu);
      CHECK(std::abs(back.latitude - p.latitude) < 1e-10);
      CHECK(std::abs(back.longitude - p.longitude) < 1e-10);
      CHECK(std::abs(back.altitude - p.altitude) < 1e-6);
      const Eigen::Matrix3d M = ecef_to_enu(datum) * ecef_to_enu(p).transpose();
      CHECK((plane.enu_at(p) - M).cwiseAbs().maxCoeff() < 1e-12);
    }
  }
  // Across the antimeridian: no zone or wrap discontinuity (UTM's failure mode).
  const LocalTangentPlane fiji(Geodetic{-17.0, 179.999, 0});
  const Eigen::Vector3d east = fiji.to_enu(Geodetic{-17.0, -179.999, 0});
  CHECK(east.x() == doctest::Approx(2 * 0.001 * M_PI / 180 * 6378137.0 * std::cos(17.0 * M_PI / 180)).epsilon(1e-2));
  CHECK(std::abs(east.y()) < 1);
}

TEST_CASE("local tangent plane: a datum that is not on Earth is refused with the reason") {
  CHECK_THROWS_WITH_AS(LocalTangentPlane(Geodetic{91, 0, 0}), doctest::Contains("latitude"), std::invalid_argument);
  CHECK_THROWS_WITH_AS(LocalTangentPlane(Geodetic{NAN, 0, 0}), doctest::Contains("finite"), std::invalid_argument);
  CHECK_THROWS_WITH_AS(LocalTangentPlane(Geodetic{0, 0, 1e9}), doctest::Contains("altitude"), std::invalid_argument);
}
