// The 3-D filter's driver (estimators/filter/spatial_fusion.hpp): start-up at the first message, predictions with the
// motion between messages and its regularized increment covariance (against the covariance propagated by hand),
// duplicates ignored, the prediction split at the stops inside the interval (the state there against the
// interpolated pose), and the state's round trip through the archive.
#include "estimators/filter/spatial_fusion.hpp"

#include <doctest/doctest.h>

#include <vector>

using namespace sextant;
using namespace sextant::filter;
using Matrix6 = SE3::Matrix6;

namespace {

SE3 pose(double x, double y, double z, double rx, double ry, double rz) {
  SE3::Vector6 xi;
  xi << x, y, z, rx, ry, rz;
  return SE3::exp(xi);
}

SpatialOdometry message(int64_t utime, const SE3& p, double increment_variance) {
  SpatialOdometry m;
  m.utime = utime;
  m.pose = p;
  m.covariance = Matrix6::Identity() * 0.01;
  m.increment_covariance = Matrix6::Identity() * increment_variance;
  return m;
}

Matrix6 initial() { return Matrix6::Identity() * 1e-4; }

const std::function<void(size_t)> kNoStop = [](size_t) { FAIL("no stop expected"); };

}  // namespace

TEST_CASE("spatial fusion: starts at the first pose, predicts with the motion and its covariance, ignores duplicates") {
  SpatialFusion f(SpatialEkfOptions{}, initial(), 1e-10);
  CHECK_FALSE(f.started());
  const SE3 T0 = pose(1, 2, 0.5, 0.1, -0.2, 0.3), T1 = pose(1.5, 2.2, 0.4, 0.12, -0.15, 0.5);
  CHECK(f.odometry(message(1'000'000, T0, 1e-3), {}, kNoStop) == SpatialOdometryOutcome::kStarted);
  CHECK(f.started());
  CHECK(f.utime() == 1'000'000);
  CHECK((f.ekf().pose().log() - T0.log()).norm() < 1e-12);
  CHECK((f.ekf().pose_covariance() - initial()).norm() == 0.0);

  CHECK(f.odometry(message(2'000'000, T1, 1e-3), {}, kNoStop) == SpatialOdometryOutcome::kPredicted);
  CHECK(f.utime() == 2'000'000);
  CHECK((f.ekf().pose().inverse() * T1).log().norm() < 1e-12);
  // P' = Ad(D^-1) P Ad(D^-1)' + Q, D = T0^-1 T1, Q the stated increment covariance (above the floor: unchanged).
  const Matrix6 F = T0.between(T1).inverse().adjoint();
  const Matrix6 expected = F * initial() * F.transpose() + Matrix6::Identity() * 1e-3;
  CHECK((f.ekf().pose_covariance() - expected).norm() < 1e-12);

  // Not newer: ignored, nothing changes.
  const Matrix6 before = f.ekf().pose_covariance();
  CHECK(f.odometry(message(2'000'000, T0, 1e-3), {}, kNoStop) == SpatialOdometryOutcome::kDuplicate);
  CHECK(f.odometry(message(1'500'000, T0, 1e-3), {}, kNoStop) == SpatialOdometryOutcome::kDuplicate);
  CHECK(f.utime() == 2'000'000);
  CHECK((f.ekf().pose().inverse() * T1).log().norm() < 1e-12);
  CHECK(f.ekf().pose_covariance() == before);

  // An increment covariance below the floor is floored (one rule, estimators/spd_matrix.hpp): a zero one adds
  // min_increment_variance on every axis.
  SpatialFusion g(SpatialEkfOptions{}, initial(), 1e-6);
  g.odometry(message(0, SE3(), 0.0), {}, kNoStop);
  g.odometry(message(1, SE3(), 0.0), {}, kNoStop);
  CHECK((g.ekf().pose_covariance() - (initial() + Matrix6::Identity() * 1e-6)).norm() < 1e-15);
}

TEST_CASE("spatial fusion: the prediction stops inside the interval at the interpolated pose, in order") {
  SpatialFusion f(SpatialEkfOptions{}, initial(), 1e-10);
  const SE3 T0 = pose(0, 0, 0, 0, 0, 0), T1 = pose(2, 1, 0.2, 0, 0.1, 0.8);
  f.odometry(message(1'000'000, T0, 1e-3), {}, kNoStop);
  // Stops: before the interval, at its start, a quarter in, half way twice, at its end: only the inner ones run.
  const std::vector<int64_t> stops = {900'000, 1'000'000, 1'250'000, 1'500'000, 1'500'000, 2'000'000};
  std::vector<size_t> reached;
  std::vector<SE3> at;
  const auto outcome = f.odometry(message(2'000'000, T1, 1e-3), stops, [&](size_t i) {
    reached.push_back(i);
    at.push_back(f.ekf().pose());
  });
  CHECK(outcome == SpatialOdometryOutcome::kPredicted);
  CHECK(reached == std::vector<size_t>{2, 3, 4});
  const SE3::Vector6 tau = T0.between(T1).log();
  REQUIRE(at.size() == 3);
  CHECK((at[0].inverse() * (T0 * SE3::exp(0.25 * tau))).log().norm() < 1e-12);
  CHECK((at[1].inverse() * (T0 * SE3::exp(0.5 * tau))).log().norm() < 1e-12);
  CHECK((at[2].inverse() * (T0 * SE3::exp(0.5 * tau))).log().norm() < 1e-12);
  CHECK((f.ekf().pose().inverse() * T1).log().norm() < 1e-12);
}

TEST_CASE("spatial fusion: a loaded state continues as the saved one") {
  SpatialFusion a(SpatialEkfOptions{}, initial(), 1e-10);
  a.odometry(message(1'000'000, pose(1, 0, 0, 0, 0, 0.1), 1e-3), {}, kNoStop);
  a.odometry(message(2'000'000, pose(2, 0.1, 0, 0, 0, 0.2), 1e-3), {}, kNoStop);
  archive::ArchiveWriter w;
  a.save(w);
  SpatialFusion b(SpatialEkfOptions{}, initial(), 1e-10);
  archive::ArchiveReader r(w.data().data(), w.data().size(), "test");
  b.load(r);
  CHECK(b.started());
  CHECK(b.utime() == a.utime());
  const SpatialOdometry next = message(3'000'000, pose(3, 0.3, 0.1, 0, 0.05, 0.3), 2e-3);
  a.odometry(next, {}, kNoStop);
  b.odometry(next, {}, kNoStop);
  CHECK((a.ekf().pose().log() - b.ekf().pose().log()).norm() == 0.0);
  CHECK(a.ekf().pose_covariance() == b.ekf().pose_covariance());
}
