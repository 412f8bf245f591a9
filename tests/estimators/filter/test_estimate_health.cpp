// Estimators refuse a step that would leave their estimate unhealthy (estimate_health.hpp): the Kalman update, the
// planar and 3-D EKF predictions and landmark additions, each leaving the state exactly as it was and counting why.
#include "estimators/filter/estimate_health.hpp"
#include "estimators/filter/kalman_update.hpp"
#include "estimators/filter/planar_ekf.hpp"
#include "estimators/filter/spatial_ekf.hpp"

#include <doctest/doctest.h>

using namespace sextant;
using namespace sextant::filter;

TEST_CASE("estimate_health: finite and positive semi-definite, or why not") {
  Eigen::Vector3d x(1, 2, 3);
  Eigen::Matrix3d P = Eigen::Vector3d(1, 2, 3).asDiagonal();
  CHECK(estimate_health(x, P, 3) == Health::kHealthy);
  CHECK(estimate_health(Eigen::Vector3d(1, NAN, 0), P, 3) == Health::kNonFinite);
  Eigen::Matrix3d Q = P;
  Q(1, 1) = -1e-3;
  CHECK(estimate_health(x, Q, 3) == Health::kIndefinite);
  Q = P;
  Q(0, 1) = Q(1, 0) = 5;  // diagonal positive, block indefinite (eigenvalues 1.5 +- 5.02)
  CHECK(estimate_health(x, Q, 3) == Health::kIndefinite);
  Q = P;
  Q(0, 2) = 1;  // not symmetric
  CHECK(estimate_health(x, Q, 3) == Health::kIndefinite);
  CHECK(std::string(health_name(Health::kNonFinite)) == "non_finite");
}

TEST_CASE("kalman_update: an update whose covariance would not be finite is refused and undone") {
  // P H' is finite, H P H' overflows: S = inf, K = 0, and the Joseph form computes inf - inf = NaN.
  Eigen::VectorXd x = Eigen::Vector2d(1, 2);
  Eigen::MatrixXd P = Eigen::Vector2d(1e200, 1e200).asDiagonal();
  Eigen::MatrixXd H(1, 2);
  H << 1e60, 0;
  const Eigen::VectorXd x0 = x;
  const Eigen::MatrixXd P0 = P;
  const UpdateResult r = kalman_update(x, P, Eigen::VectorXd::Constant(1, 1.0), H, Eigen::MatrixXd::Identity(1, 1), 0);
  CHECK_FALSE(r.accepted);
  CHECK((r.reason == UpdateReason::kNonFinite || r.reason == UpdateReason::kIndefinite));
  CHECK(x == x0);
  CHECK(P == P0);
}

TEST_CASE(
    "planar EKF: a prediction that would overflow is refused, counted, and the filter goes on from where it was") {
  PlanarEkf ekf;
  ekf.initialize(SE2(1, 2, 0.3), Eigen::Matrix3d::Identity() * 0.01);
  ekf.predict(SE2(1, 0, 0), Eigen::Matrix3d::Identity() * 1e-4);
  const Eigen::VectorXd x0 = ekf.state();
  const Eigen::MatrixXd P0 = ekf.covariance();
  CHECK(ekf.predict(SE2(1e308, 1e308, 0), Eigen::Matrix3d::Identity() * 1e-4) == Health::kNonFinite);
  CHECK(ekf.predict(SE2(1, 0, 0), Eigen::Matrix3d::Identity() * 1e308 * 10) != Health::kHealthy);
  CHECK(ekf.state() == x0);
  CHECK(ekf.covariance() == P0);
  CHECK(ekf.refusals().non_finite == 2);
  CHECK(ekf.predict(SE2(1, 0, 0), Eigen::Matrix3d::Identity() * 1e-4) == Health::kHealthy);
  CHECK(ekf.state()[0] != x0[0]);
}

TEST_CASE("planar EKF: a landmark sighted at 1e308 m never joins the state") {
  PlanarEkf ekf;
  ekf.initialize(SE2(0, 0, 0.1), Eigen::Matrix3d::Identity() * 0.01);
  const UpdateResult r = ekf.observe(7, 1e308, 0.5, Eigen::Matrix2d::Identity() * 0.01);
  CHECK_FALSE(r.accepted);
  CHECK(r.reason == UpdateReason::kNonFinite);
  CHECK(ekf.landmark_count() == 0);
  CHECK(ekf.state().allFinite());
  CHECK(ekf.refusals().non_finite == 1);
}

TEST_CASE("3-D EKF: predictions and landmarks that would overflow are refused and counted") {
  SpatialEkf ekf;
  ekf.initialize(SE3(), SpatialEkf::Matrix6::Identity() * 0.01);
  SpatialEkf::Matrix6 huge = SpatialEkf::Matrix6::Identity() * 1e308;
  huge(0, 0) = 1e308 * 10;  // inf
  CHECK(ekf.predict(SE3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(1, 0, 0)), huge) == Health::kNonFinite);
  CHECK(ekf.pose().translation().norm() == 0);
  const UpdateResult r = ekf.observe(3, Eigen::Vector3d(1e308, 0.1, 0.1), Eigen::Matrix3d::Identity() * 0.01);
  CHECK_FALSE(r.accepted);
  CHECK(ekf.landmark_count() == 0);
  CHECK(ekf.refusals().non_finite == 2);
}
