// Passive-sensor geometry: the bearing model's Jacobian, triangulation on an exact case, its covariance against
// Monte Carlo, degenerate geometry, and the Gaussian divergences against numerical integration.
#include "assoc/bearing_model.hpp"
#include "assoc/field_of_view.hpp"
#include "assoc/gaussian_divergence.hpp"
#include "assoc/triangulation.hpp"

#include <doctest/doctest.h>

#include <Eigen/LU>

#include <cmath>
#include <random>
#include <stdexcept>

using namespace sextant::assoc;

namespace {
// The passive-association paper's sensors (sim/assoc_experiment.hpp).
const Eigen::Vector3d kSensors[3] = {{30, 0, 0.1}, {0, 30, 0.1}, {0, 0, 0}};

std::vector<BearingObservation> observe(const Eigen::Vector3d& target, double sigma, std::mt19937* rng) {
  std::vector<BearingObservation> obs;
  std::normal_distribution<double> n(0, sigma);
  for (const auto& s : kSensors) {
    const auto h = bearing(s, target);
    BearingObservation o;
    o.sensor = s;
    o.azimuth = (*h)[0] + (rng ? n(*rng) : 0.0);
    o.elevation = (*h)[1] + (rng ? n(*rng) : 0.0);
    o.covariance = Eigen::Matrix2d::Identity() * sigma * sigma;
    obs.push_back(o);
  }
  return obs;
}
}  // namespace

TEST_CASE("bearing Jacobian against central differences") {
  const Eigen::Vector3d s(1, -2, 0.5), x(7, 3, 4);
  Eigen::Matrix<double, 2, 3> J;
  bearing(s, x, &J);
  for (int c = 0; c < 3; ++c) {
    Eigen::Vector3d e = Eigen::Vector3d::Zero();
    e[c] = 1e-6;
    CHECK(((*bearing(s, x + e) - *bearing(s, x - e)) / 2e-6 - J.col(c)).norm() < 1e-8);
  }
  CHECK_FALSE(bearing(s, s + Eigen::Vector3d(0, 0, 5)).has_value());  // on the sensor's vertical
}

TEST_CASE("noise-free bearings triangulate to the target exactly") {
  const Eigen::Vector3d target(10, 12, 5);
  const auto obs = observe(target, 0.005, nullptr);
  const auto lin = triangulate_linear(obs);
  REQUIRE(lin.valid);
  CHECK((lin.position - target).norm() < 1e-9);
  const auto ml = triangulate(obs);
  REQUIRE(ml.valid);
  CHECK((ml.position - target).norm() < 1e-9);
  CHECK(ml.residual < 1e-15);
}

TEST_CASE("the triangulation covariance matches Monte Carlo") {
  std::mt19937 rng(17);
  const Eigen::Vector3d target(10, 12, 5);
  const int runs = 4000;
  std::vector<Eigen::Vector3d> est;
  Eigen::Matrix3d predicted = Eigen::Matrix3d::Zero();
  for (int k = 0; k < runs; ++k) {
    const auto t = triangulate(observe(target, 0.005, &rng));
    REQUIRE(t.valid);
    est.push_back(t.position);
    predicted += t.covariance / runs;
  }
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& e : est) mean += e / runs;
  Eigen::Matrix3d sample = Eigen::Matrix3d::Zero();
  for (const auto& e : est) sample += (e - mean) * (e - mean).transpose() / (runs - 1);
  CHECK((mean - target).norm() < 0.05);
  CHECK((sample - predicted).norm() < 0.1 * predicted.norm());
}

TEST_CASE("prepared-bearing linearization equals the bearing model's residual and Jacobian") {
  // add_observation takes the residual angles as the angles between measured and predicted direction (a series
  // for small ones); the reference wraps z - h(x) with h and J from bearing().  Small and large residuals (the
  // series and the atan2 fallback), azimuths across +-pi.
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> u(-1, 1);
  const Eigen::Matrix2d Ri = Eigen::Vector2d(1 / 2.5e-5, 1 / 1e-4).asDiagonal();
  int small = 0, large = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const Eigen::Vector3d sensor(10 * u(rng), 10 * u(rng), 0.1 * u(rng));
    const Eigen::Vector3d x =
        sensor + Eigen::Vector3d(-20 + 2 * u(rng), 3 * u(rng), 5 + 2 * u(rng));  // azimuth near pi
    const auto h = *bearing(sensor, x);
    const double spread = trial % 2 ? 0.01 : 0.5;
    BearingObservation o{sensor, h[0] + spread * u(rng), h[1] + spread * u(rng), Eigen::Matrix2d::Identity()};
    if (o.azimuth > M_PI) o.azimuth -= 2 * M_PI;
    Eigen::Matrix<double, 2, 3> J;
    const auto hx = *bearing(sensor, x, &J);
    const Eigen::Vector2d nu(std::remainder(o.azimuth - hx[0], 2 * M_PI), o.elevation - hx[1]);
    (std::abs(nu[0]) < 0.04 && std::abs(nu[1]) < 0.04 ? small : large) += 1;
    NormalEquations n;
    REQUIRE(add_observation(n, PreparedBearing(o, Ri), x));
    CAPTURE(trial);
    CHECK((n.information - J.transpose() * Ri * J).norm() <= 1e-9 * (J.transpose() * Ri * J).norm());
    CHECK((n.gradient - J.transpose() * Ri * nu).norm() <= 1e-9 * (J.transpose() * Ri * nu).norm() + 1e-9);
    CHECK(n.residual == doctest::Approx(nu.dot(Ri * nu)).epsilon(1e-9));
  }
  CHECK(small > 100);
  CHECK(large > 100);
  // On the sensor's vertical: refused, the normal equations untouched.
  NormalEquations n;
  CHECK_FALSE(add_observation(n, PreparedBearing({kSensors[0], 0.3, 0.2, Eigen::Matrix2d::Identity()}, Ri),
                              kSensors[0] + Eigen::Vector3d(0, 0, 5)));
  CHECK(n.residual == 0.0);
  CHECK(n.information.isZero());
}

TEST_CASE("degenerate geometry is flagged, never NaN") {
  std::vector<BearingObservation> one(1);
  CHECK_FALSE(triangulate(one).valid);
  CHECK(triangulate(one).reason == "fewer than 2 sensors");
  // Two sensors and a target on the line through them: the lines of sight coincide.
  std::vector<BearingObservation> parallel;
  for (const Eigen::Vector3d& s : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(10, 0, 0)}) {
    const auto h = bearing(s, Eigen::Vector3d(50, 0, 0));
    parallel.push_back({s, (*h)[0], (*h)[1], Eigen::Matrix2d::Identity() * 1e-6});
  }
  const auto t = triangulate(parallel);
  CHECK_FALSE(t.valid);
  CHECK(t.reason.find("ill-conditioned") != std::string::npos);
  CHECK(t.position.allFinite());
}

TEST_CASE("Renyi divergence: closed form against numerical integration, its alpha -> 1 limit and equal covariances") {
  Eigen::Vector2d m1(0.1, -0.2), m2(0.4, 0.1);
  Eigen::Matrix2d S1, S2;
  S1 << 0.2, 0.05, 0.05, 0.1;
  S2 << 0.15, -0.03, -0.03, 0.25;
  auto pdf = [](const Eigen::Vector2d& x, const Eigen::Vector2d& m, const Eigen::Matrix2d& S) {
    const Eigen::Vector2d d = x - m;
    return std::exp(-0.5 * d.dot(S.inverse() * d)) / (2 * M_PI * std::sqrt(S.determinant()));
  };
  for (double alpha : {0.3, 0.5, 0.8}) {
    // D_a = 1/(a - 1) ln integral p^a q^(1-a), by the midpoint rule on a wide grid.
    double integral = 0;
    const double h = 0.01;
    for (double x = -3; x < 3.5; x += h)
      for (double y = -3; y < 3.5; y += h) {
        const Eigen::Vector2d p(x + h / 2, y + h / 2);
        integral += std::pow(pdf(p, m1, S1), alpha) * std::pow(pdf(p, m2, S2), 1 - alpha) * h * h;
      }
    CHECK(renyi_divergence(m1, S1, m2, S2, alpha) == doctest::Approx(std::log(integral) / (alpha - 1)).epsilon(1e-5));
  }
  CHECK(renyi_divergence(m1, S1, m2, S2, 0.99999) == doctest::Approx(kl_divergence(m1, S1, m2, S2)).epsilon(1e-4));
  const double maha = (m1 - m2).dot(S1.inverse() * (m1 - m2));
  CHECK(renyi_divergence(m1, S1, m2, S1, 0.3) == doctest::Approx(0.15 * maha));
  CHECK(symmetric_renyi_divergence(m1, S1, m2, S2, 0.5) ==
        doctest::Approx(symmetric_renyi_divergence(m2, S2, m1, S1, 0.5)));
  CHECK(std::isinf(renyi_divergence(m1, S1, m2, -S2, 0.5)));
  CHECK(std::isinf(renyi_divergence(m1, S1, m2, S2, 1.5)));
}

TEST_CASE("field of view of a box region: bounds and area against the geometry, padding, a sensor inside") {
  // Sensor at the origin, region x in [10, 20], y in [-5, 5], z in [0, 10]: azimuth within +-atan(5/10) (near
  // corners), elevation from 0 (the floor) to 45 degrees (the top at the nearest point (10, 0, 10)).
  const Eigen::Vector3d lo(10, -5, 0), hi(20, 5, 10);
  const auto f = field_of_view(Eigen::Vector3d::Zero(), lo, hi, 0.0);
  CHECK(f.centre_azimuth == doctest::Approx(0.0));
  CHECK(f.azimuth_lo == doctest::Approx(-std::atan(0.5)));
  CHECK(f.azimuth_hi == doctest::Approx(std::atan(0.5)));
  CHECK(f.elevation_lo == doctest::Approx(0.0));
  CHECK(f.elevation_hi == doctest::Approx(M_PI / 4));
  CHECK(f.area() == doctest::Approx(2 * std::atan(0.5) * M_PI / 4));
  const auto padded = field_of_view(Eigen::Vector3d::Zero(), lo, hi, 0.01);
  CHECK(padded.area() == doctest::Approx((2 * std::atan(0.5) + 0.02) * (M_PI / 4 + 0.02)));
  // Every direction to a point of the region is inside (relative azimuth, elevation).
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0, 1);
  for (int k = 0; k < 200; ++k) {
    const Eigen::Vector3d x = lo + (hi - lo).cwiseProduct(Eigen::Vector3d(u(rng), u(rng), u(rng)));
    const auto h = *bearing(Eigen::Vector3d::Zero(), x);
    CHECK(h[0] - f.centre_azimuth >= f.azimuth_lo - 1e-12);
    CHECK(h[0] - f.centre_azimuth <= f.azimuth_hi + 1e-12);
    CHECK(h[1] >= f.elevation_lo - 1e-12);
    CHECK(h[1] <= f.elevation_hi + 1e-12);
  }
  // A sensor inside the region's horizontal extent sees every azimuth.
  const auto inside = field_of_view(Eigen::Vector3d(15, 0, -1), lo, hi, 0.01);
  CHECK(inside.azimuth_hi - inside.azimuth_lo == doctest::Approx(2 * M_PI));
  CHECK(inside.elevation_hi <= M_PI / 2);
  CHECK_THROWS_AS(field_of_view(Eigen::Vector3d::Zero(), hi, lo, 0.0), std::invalid_argument);
  CHECK_THROWS_AS(field_of_view(Eigen::Vector3d(NAN, 0, 0), lo, hi, 0.0), std::invalid_argument);
}
