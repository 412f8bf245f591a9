#pragma once
// The EuRoC V1_02 excerpt of the shared data (inertial/euroc_v1_02_excerpt: imu0/data.csv at 200 Hz, gt0/data.csv
// at 40 Hz with the true biases), read here for the tests with a plain CSV reader of their own.
#include "estimators/inertial/imu_preintegration.hpp"

#include <doctest/doctest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace sextant::test {

struct EurocExcerpt {
  struct Imu {
    double t;
    Eigen::Vector3d w, a;
  };
  struct Truth {
    double t;
    Eigen::Vector3d p;
    Eigen::Quaterniond q;
    Eigen::Vector3d v, b_g, b_a;
  };
  std::vector<Imu> imu;
  std::vector<Truth> truth;

  static std::string dir() { return std::string(SEXTANT_SHARED_DIR) + "/data/inertial/euroc_v1_02_excerpt"; }

  static std::vector<std::vector<double>> rows(const std::string& path, size_t columns) {
    std::ifstream in(path);
    REQUIRE_MESSAGE(in.good(), "cannot read ", path);
    std::vector<std::vector<double>> out;
    std::string line;
    while (std::getline(in, line)) {
      if (line.empty() || line[0] == '#') continue;
      std::replace(line.begin(), line.end(), ',', ' ');
      std::istringstream s(line);
      long long ns;
      s >> ns;
      std::vector<double> r{static_cast<double>(ns - 1403715500000000000LL) * 1e-9};  // seconds, digits kept
      double x;
      while (s >> x) r.push_back(x);
      REQUIRE(r.size() == columns);
      out.push_back(r);
    }
    return out;
  }

  static EurocExcerpt load() {
    EurocExcerpt e;
    for (const auto& r : rows(dir() + "/imu0/data.csv", 7))
      e.imu.push_back({r[0], {r[1], r[2], r[3]}, {r[4], r[5], r[6]}});
    for (const auto& r : rows(dir() + "/gt0/data.csv", 17))
      e.truth.push_back({r[0],
                         {r[1], r[2], r[3]},
                         Eigen::Quaterniond(r[4], r[5], r[6], r[7]).normalized(),
                         {r[8], r[9], r[10]},
                         {r[11], r[12], r[13]},
                         {r[14], r[15], r[16]}});
    REQUIRE(e.imu.size() == 7999);  // 40 s at 200 Hz
    REQUIRE(e.truth.size() == 3340);
    return e;
  }

  /// Preintegration of the samples over [t0, t1], each sample held until the next one (clipped to the interval).
  inertial::ImuPreintegration preintegrate(double t0, double t1, const inertial::ImuBias& b) const {
    inertial::ImuPreintegration pim(b);
    for (size_t k = 0; k + 1 < imu.size(); ++k) {
      const double a = std::max(imu[k].t, t0), z = std::min(imu[k + 1].t, t1);
      if (z > a + 1e-12) pim.integrate(imu[k].w, imu[k].a, z - a);
    }
    return pim;
  }
};

}  // namespace sextant::test
