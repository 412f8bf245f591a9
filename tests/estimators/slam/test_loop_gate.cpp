// The loop gate against a Mahalanobis distance worked out by hand (planar and 3-D), and a loop moved onto keyframes
// through the odometry (composition by hand) with its information widened by a thinned end's covariance.
#include "estimators/slam/loop_gate.hpp"

#include "estimators/lie/se2.hpp"

#include <doctest/doctest.h>

#include <cmath>

using namespace sextant;
using namespace sextant::slam;

namespace {

SE3 planar_pose(double x, double y, double yaw) { return SE2(x, y, yaw).to_se3(); }

}  // namespace

TEST_CASE("loop gate: d2 is the hand-computed Mahalanobis distance with the odometry path scaled by k^2") {
  // z = (1, 0), estimate (1.2, 0.1): e = (0.2, 0.1, 0).  Loop covariance diag(0.04, 0.01, 0.01) (x, y, yaw); path
  // covariance diag(0.01, 0.02, 0) with k = 2: S = diag(0.04 + 4 * 0.01, 0.01 + 4 * 0.02, 0.01) = (0.08, 0.09, 0.01),
  // d2 = 0.2^2 / 0.08 + 0.1^2 / 0.09 = 0.5 + 0.1111...
  const double expected = 0.04 / 0.08 + 0.01 / 0.09;
  Matrix6d information = Matrix6d::Identity() * 100;
  information(0, 0) = 25, information(1, 1) = 100, information(5, 5) = 100;
  Matrix6d path = Matrix6d::Zero();
  path(0, 0) = 0.01, path(1, 1) = 0.02;
  const TrackPoint here{0, SE3(), Matrix6d::Zero()};
  for (const bool planar : {true, false}) {
    CAPTURE(planar);
    const KeyframeLoop loop = loop_on_keyframes(planar, planar_pose(1, 0, 0), information, here, here);
    CHECK_FALSE(loop.widened);
    CHECK(loop.information == information);
    // 3-D: the other axes have no error, so they add nothing (S's other diagonal entries are 0.01 + 0).
    const double d2 = loop_mahalanobis(planar, loop, planar_pose(1.2, 0.1, 0), path, 2.0);
    CHECK(d2 == doctest::Approx(expected).epsilon(1e-12));
  }
  // Without the path the same error is far outside a 0.999 gate (chi2_3 = 16.27): 0.04 / 0.04 + 0.01 / 0.01 = 2.
  const KeyframeLoop loop = loop_on_keyframes(true, planar_pose(1, 0, 0), information, here, here);
  CHECK(loop_mahalanobis(true, loop, planar_pose(1.2, 0.1, 0), Matrix6d::Zero(), 2.0) == doctest::Approx(2.0));
  // A heading error: e = (0, 0, 0.05) over yaw variance 0.01: d2 = 0.25.
  CHECK(loop_mahalanobis(true, loop, planar_pose(1, 0, 0.05), Matrix6d::Zero(), 2.0) == doctest::Approx(0.25));
}

TEST_CASE("loop gate: a loop between two times is moved onto their keyframes, and a thinned end widens it") {
  // From-end: the keyframe, then a quarter turn to the loop's time; to-end: 0.3 m ahead of its keyframe along y.
  // z' = D_from z D_to^-1: the quarter turn takes z = (1, 0) to (0, 1) heading pi/2, and D_to^-1 = (0, -0.3) in that
  // heading is (0.3, 0) in the keyframe's frame: (0.3, 1), heading pi/2.
  const TrackPoint from{0, planar_pose(0, 0, M_PI / 2), Matrix6d::Zero()};
  TrackPoint to{3, planar_pose(0, 0.3, 0), Matrix6d::Zero()};
  Matrix6d information = Matrix6d::Identity() * 10;
  KeyframeLoop loop = loop_on_keyframes(true, planar_pose(1, 0, 0), information, from, to);
  const SE2 z = SE2::from_se3(loop.z);
  CHECK(z.translation().x() == doctest::Approx(0.3));
  CHECK(z.translation().y() == doctest::Approx(1.0));
  CHECK(z.angle() == doctest::Approx(M_PI / 2));

  // The to-end came through a thinned keyframe with covariance diag(0.1, 0.2, 0.3): Sigma' = 0.1 I + that, over
  // x, y, yaw, so Omega' = diag(1 / 0.2, 1 / 0.3, 1 / 0.4), zero on the axes a planar body does not use.
  to.covariance.setZero();
  to.covariance(0, 0) = 0.1, to.covariance(1, 1) = 0.2, to.covariance(5, 5) = 0.3;
  loop = loop_on_keyframes(true, planar_pose(1, 0, 0), information, from, to);
  CHECK(loop.widened);
  CHECK(loop.information(0, 0) == doctest::Approx(5.0));
  CHECK(loop.information(1, 1) == doctest::Approx(1 / 0.3));
  CHECK(loop.information(5, 5) == doctest::Approx(2.5));
  CHECK(loop.information(2, 2) == 0.0);
  CHECK(std::abs(loop.information(0, 1)) < 1e-12);
  // 3-D: the same on the x, y, yaw axes; z, roll, pitch keep 1 / 0.1.
  loop = loop_on_keyframes(false, planar_pose(1, 0, 0), information, from, to);
  CHECK(loop.information(0, 0) == doctest::Approx(5.0));
  CHECK(loop.information(5, 5) == doctest::Approx(2.5));
  CHECK(loop.information(2, 2) == doctest::Approx(10.0));
}

TEST_CASE("loop gate: the landing sigma is the largest translation standard deviation the thinned ends add") {
  // From-end x, y block [[0.05, 0.02], [0.02, 0.05]], to-end x variance 0.02: the sum [[0.07, 0.02], [0.02, 0.05]]
  // has eigenvalues 0.06 +- sqrt(0.01^2 + 0.02^2), so sigma = sqrt(0.06 + 0.0223607) = 0.286987.  The heading's
  // variance (5 rad^2) is not a translation and does not count.
  TrackPoint from{0, SE3(), Matrix6d::Zero()}, to{1, SE3(), Matrix6d::Zero()};
  CHECK(landing_sigma(from, to) == 0.0);
  from.covariance(0, 0) = from.covariance(1, 1) = 0.05;
  from.covariance(0, 1) = from.covariance(1, 0) = 0.02;
  from.covariance(5, 5) = 5;
  to.covariance(0, 0) = 0.02;
  CHECK(landing_sigma(from, to) == doctest::Approx(std::sqrt(0.06 + std::sqrt(0.0005))).epsilon(1e-12));
  CHECK(landing_sigma(to, from) == doctest::Approx(landing_sigma(from, to)).epsilon(1e-15));
  // A 3-D end: the vertical counts as well.
  to.covariance(2, 2) = 0.5;
  CHECK(landing_sigma(from, to) == doctest::Approx(std::sqrt(0.5)).epsilon(1e-12));
}
