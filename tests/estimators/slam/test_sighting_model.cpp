// A landmark sighting anchored between keyframe and odometry: where its first sighting puts the landmark (by hand),
// its residual, and the gate's d2 against S = R + k^2 J_D Sigma_D J_D' + J_K P_K J_K' + J_p P_p J_p' with every
// Jacobian taken by central differences of a range/bearing written out here (not the factor's analytic one).
#include "estimators/slam/sighting_model.hpp"

#include "estimators/lie/planar_axes.hpp"
#include "estimators/lie/se2.hpp"

#include <doctest/doctest.h>

#include <Eigen/Cholesky>

#include <cmath>

using namespace sextant;
using namespace sextant::slam;

namespace {

/// Range and bearing of `landmark` from the sensor at K D S (planar poses).
Eigen::Vector2d range_bearing(const SE2& K, const SE2& D, const SE2& S, const Eigen::Vector2d& landmark) {
  const SE2 sensor = K * D * S;
  const Eigen::Vector2d p = sensor.rotation().matrix().transpose() * (landmark - sensor.translation());
  return {p.norm(), std::atan2(p.y(), p.x())};
}

}  // namespace

TEST_CASE("sighting model: the first sighting places the landmark by hand, and the gate's d2 matches a numeric S") {
  const SE2 K(2.0, -1.0, 0.3), D(1.0, 0.2, 0.4), S(0.5, 0.0, -0.2);
  Eigen::Matrix3d sigma_d;
  sigma_d << 0.02, 0.003, 0.0, 0.003, 0.04, 0.001, 0.0, 0.001, 0.005;
  const TrackPoint anchor{0, D.to_se3(), embed_planar(sigma_d)};
  const SightingModel model(true, K.to_se3(), anchor, S.to_se3());
  CHECK(model.dimension() == 2);

  LandmarkSighting s;
  s.id = 7, s.range = 4.0, s.azimuth = 0.6;
  s.covariance = Eigen::Vector3d(0.01, 0.0004, 1.0).asDiagonal();
  Eigen::VectorXd z;
  Eigen::MatrixXd R;
  REQUIRE(model.measurement(s, z, R));
  CHECK(R.rows() == 2);
  // The landmark where the sighting puts it: the sensor's pose K D S, then range along the azimuth.
  const SE2 sensor = K * D * S;
  const Eigen::Vector2d expected =
      sensor.translation() + 4.0 * Eigen::Vector2d(std::cos(sensor.angle() + 0.6), std::sin(sensor.angle() + 0.6));
  const Eigen::Vector3d placed = model.landmark_from(s);
  CHECK(placed.x() == doctest::Approx(expected.x()).epsilon(1e-12));
  CHECK(placed.y() == doctest::Approx(expected.y()).epsilon(1e-12));
  CHECK(placed.z() == 0.0);
  CHECK(model.evaluate(z, placed).error.norm() < 1e-12);

  // A landmark estimate off the sighting: the residual h - z and d2 against S from numeric Jacobians.
  const Eigen::Vector2d landmark = expected + Eigen::Vector2d(0.3, -0.2);
  const SightingModel::Evaluation ev = model.evaluate(z, Eigen::Vector3d(landmark.x(), landmark.y(), 0));
  const Eigen::Vector2d h = range_bearing(K, D, S, landmark);
  CHECK(ev.error(0) == doctest::Approx(h(0) - 4.0).epsilon(1e-12));
  CHECK(ev.error(1) == doctest::Approx(h(1) - 0.6).epsilon(1e-12));

  const double eps = 1e-6;
  Eigen::Matrix<double, 2, 3> JD, JK;
  Eigen::Matrix2d Jp;
  for (int i = 0; i < 3; ++i) {
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    d(i) = eps;
    const SE2 plus(d(0), d(1), d(2)), minus(-d(0), -d(1), -d(2));
    JD.col(i) = (range_bearing(K, D * plus, S, landmark) - range_bearing(K, D * minus, S, landmark)) / (2 * eps);
    JK.col(i) = (range_bearing(K * plus, D, S, landmark) - range_bearing(K * minus, D, S, landmark)) / (2 * eps);
  }
  for (int i = 0; i < 2; ++i) {
    Eigen::Vector2d d = Eigen::Vector2d::Zero();
    d(i) = eps;
    Jp.col(i) = (range_bearing(K, D, S, landmark + d) - range_bearing(K, D, S, landmark - d)) / (2 * eps);
  }
  Eigen::Matrix3d P_K;
  P_K << 0.05, 0.01, 0.0, 0.01, 0.03, 0.0, 0.0, 0.0, 0.002;
  Eigen::Matrix2d P_p;
  P_p << 0.2, 0.05, 0.05, 0.1;
  const double k = 3.0;
  const Eigen::Matrix2d Rm = R;
  const Eigen::Matrix2d Sfull =
      Rm + k * k * JD * sigma_d * JD.transpose() + JK * P_K * JK.transpose() + Jp * P_p * Jp.transpose();
  const Eigen::Vector2d e(h(0) - 4.0, h(1) - 0.6);
  const double d2 = e.dot(Sfull.ldlt().solve(e));
  CHECK(model.mahalanobis(ev, R, k, P_p, P_K) == doctest::Approx(d2).epsilon(1e-6));
  // Without the marginals (landmark or keyframe not determined) they are left out of S.
  const Eigen::Matrix2d Sodo = Rm + k * k * JD * sigma_d * JD.transpose();
  CHECK(model.mahalanobis(ev, R, k, Eigen::MatrixXd(), Eigen::MatrixXd()) ==
        doctest::Approx(e.dot(Sodo.ldlt().solve(e))).epsilon(1e-6));
  // The factor's information: (R + J_D Sigma_D J_D')^-1 (odometry unscaled).
  const Eigen::Matrix2d info = (Rm + JD * sigma_d * JD.transpose()).inverse();
  CHECK((model.information(ev, R) - info).norm() < 1e-6 * info.norm());
  CHECK(model.information(ev, R) == model.information(ev, R).transpose());  // exactly symmetric
  // The factor's sensor offset is D S.
  CHECK((model.sensor_in_keyframe().translation() - (D * S).to_se3().translation()).norm() < 1e-12);
}

TEST_CASE("sighting model: malformed sightings are refused, and a 3-D sighting has range, azimuth and elevation") {
  const TrackPoint anchor{0, SE3(), Matrix6d::Zero()};
  const SightingModel planar(true, SE3(), anchor, SE3());
  LandmarkSighting s;
  s.range = 2, s.azimuth = 0.1;
  s.covariance = Eigen::Matrix3d::Identity() * 0.01;
  Eigen::VectorXd z;
  Eigen::MatrixXd R;
  CHECK(planar.measurement(s, z, R));
  LandmarkSighting bad = s;
  bad.range = 0;
  CHECK_FALSE(planar.measurement(bad, z, R));
  bad = s, bad.azimuth = std::nan("");
  CHECK_FALSE(planar.measurement(bad, z, R));
  bad = s, bad.covariance(1, 1) = -1;
  CHECK_FALSE(planar.measurement(bad, z, R));
  bad = s, bad.covariance(2, 2) = -1;  // elevation's variance: not used on a planar body
  CHECK(planar.measurement(bad, z, R));

  const SightingModel spatial(false, SE3(), anchor, SE3());
  CHECK(spatial.dimension() == 3);
  CHECK_FALSE(spatial.measurement(bad, z, R));
  s.elevation = 0.5;
  REQUIRE(spatial.measurement(s, z, R));
  const Eigen::Vector3d l = spatial.landmark_from(s);
  CHECK(l.x() == doctest::Approx(2 * std::cos(0.5) * std::cos(0.1)));
  CHECK(l.y() == doctest::Approx(2 * std::cos(0.5) * std::sin(0.1)));
  CHECK(l.z() == doctest::Approx(2 * std::sin(0.5)));
}
