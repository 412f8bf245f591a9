#include "estimators/lie/unit_quaternion.hpp"

#include <doctest/doctest.h>

#include <limits>

using sextant::unit_quaternion;

TEST_CASE("unit quaternion: the rotation any scale spells, none for zeros or non-finite components") {
  const Eigen::Quaterniond r(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, -2, 0.5).normalized()));
  for (const double scale : {1.0, 3.5, 1e300, 1e-300}) {
    CAPTURE(scale);
    const auto q = unit_quaternion(scale * r.w(), scale * r.x(), scale * r.y(), scale * r.z());
    REQUIRE(q);
    CHECK(std::abs(q->norm() - 1) < 1e-15);
    CHECK(q->angularDistance(r) < 1e-9);
  }
  // Denormals: the plain norm underflows to zero; the scaled one still gives the rotation.
  const double d = std::numeric_limits<double>::denorm_min();
  const auto q = unit_quaternion(d, 0, 0, d);
  REQUIRE(q);
  CHECK(q->angularDistance(Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()))) < 1e-12);
  CHECK_FALSE(unit_quaternion(0, 0, 0, 0));
  CHECK_FALSE(unit_quaternion(std::numeric_limits<double>::quiet_NaN(), 0, 0, 1));
  CHECK_FALSE(unit_quaternion(std::numeric_limits<double>::infinity(), 0, 0, 1));
  CHECK_FALSE(unit_quaternion(1e308, 1e308, -std::numeric_limits<double>::infinity(), 0));
}
