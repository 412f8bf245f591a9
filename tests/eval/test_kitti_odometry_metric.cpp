// The KITTI odometry error against closed forms: a uniformly scaled straight run (translation only) and a run whose
// heading drifts at a constant rate (rotation only), plus the refusals that keep a figure from meaning nothing.
#include "eval/kitti_odometry_metric.hpp"
#include "cli/trajectory_evaluation.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <stdexcept>

using namespace sextant::tools;
using sextant::engine::Pose;

namespace {
// n poses 1 m apart along x, heading along x.
std::vector<Pose> straight_run(size_t n) {
  std::vector<Pose> poses(n);
  for (size_t i = 0; i < n; ++i) poses[i].position = {static_cast<double>(i), 0, 0};
  return poses;
}
}  // namespace

TEST_CASE("KITTI error of a scaled straight run: each segment's error is 1 % of its true span over L") {
  // Path distances are integers, so the segment (f, L) ends at l = f + L + 1 (the first frame beyond f + L) and spans
  // L + 1 m; the estimate travels 1.01 (L + 1), so |t_E| = 0.01 (L + 1) and the segment's error is 0.01 (L + 1) / L.
  const size_t n = 1001;
  const auto gt = straight_run(n);
  auto est = gt;
  for (auto& p : est) p.position *= 1.01;
  const KittiOdometryError e = kitti_odometry_error(gt, est);
  double sum = 0;
  size_t count = 0;
  for (int L = 100; L <= 800; L += 100)
    for (size_t f = 0; f + L + 1 <= n - 1; f += 10) {
      sum += 0.01 * (L + 1) / L;
      ++count;
    }
  REQUIRE(e.segments.size() == count);
  CHECK(e.translation_percent == doctest::Approx(100.0 * sum / count).epsilon(1e-12));
  CHECK(e.rotation_deg_per_m == doctest::Approx(0.0));
  // Segment order and bookkeeping: starts every 10th frame, each with the eight lengths that fit.
  CHECK(e.segments.front().first_frame == 0);
  CHECK(e.segments.front().length == 100);
  CHECK(e.segments.front().translation == doctest::Approx(0.01 * 101 / 100).epsilon(1e-12));
}

TEST_CASE("KITTI error of a run whose heading drifts at a constant rate: angle(R_E) / L = rate (L + 1) / L") {
  const size_t n = 901;
  const double rate = 1e-4;  // rad per frame (1 m per frame)
  const auto gt = straight_run(n);
  auto est = gt;
  for (size_t i = 0; i < n; ++i)
    est[i].orientation = Eigen::AngleAxisd(rate * static_cast<double>(i), Eigen::Vector3d::UnitZ());
  const KittiOdometryError e = kitti_odometry_error(gt, est);
  double sum = 0;
  size_t count = 0;
  for (int L = 100; L <= 800; L += 100)
    for (size_t f = 0; f + L + 1 <= n - 1; f += 10) {
      sum += rate * (L + 1) / L;
      ++count;
    }
  REQUIRE(e.segments.size() == count);
  CHECK(e.rotation_deg_per_m == doctest::Approx((sum / count) * 180.0 / M_PI).epsilon(1e-9));
}

TEST_CASE("KITTI error refuses what would read as perfect: mismatched lengths, a run shorter than 100 m, bad options") {
  const auto gt = straight_run(200);
  CHECK_THROWS_AS(kitti_odometry_error(gt, straight_run(199)), std::invalid_argument);
  CHECK_THROWS_AS(kitti_odometry_error(straight_run(100), straight_run(100)), std::invalid_argument);  // 99 m
  CHECK_THROWS_AS(kitti_odometry_error(straight_run(1), straight_run(1)), std::invalid_argument);
  KittiMetricOptions zero_step;
  zero_step.step = 0;
  CHECK_THROWS_AS(kitti_odometry_error(gt, gt, zero_step), std::invalid_argument);
  KittiMetricOptions negative;
  negative.lengths = {-5};
  CHECK_THROWS_AS(kitti_odometry_error(gt, gt, negative), std::invalid_argument);
  // 101 m: exactly the segments that start at frame 0 with L = 100 (frame 101 is beyond 100 m) and none after.
  const auto e = kitti_odometry_error(straight_run(102), straight_run(102));
  CHECK(e.segments.size() == 1);
  CHECK(e.translation_percent == 0.0);
}

TEST_CASE("sextant eval reports the KITTI error over the associated poses when the ground truth is long enough") {
  std::vector<StampedPose> gt, est;
  for (size_t i = 0; i < 1001; ++i) {
    StampedPose s;
    s.t = 0.1 * static_cast<double>(i);
    s.pose.position = {static_cast<double>(i), 0, 0};
    gt.push_back(s);
    s.pose.position *= 1.02;
    est.push_back(s);
  }
  const Evaluation e = evaluate_trajectory(gt, est);
  REQUIRE(e.kitti.has_value());
  std::vector<Pose> g, x;
  for (size_t i = 0; i < gt.size(); ++i) {
    g.push_back(gt[i].pose);
    x.push_back(est[i].pose);
  }
  CHECK(e.kitti->translation_percent == doctest::Approx(kitti_odometry_error(g, x).translation_percent));
  CHECK(e.kitti->translation_percent > 2.0);
  // 50 m of ground truth: no KITTI figure, and the summary says so with null and zero segments.
  gt.resize(51);
  est.resize(51);
  const Evaluation short_run = evaluate_trajectory(gt, est);
  CHECK_FALSE(short_run.kitti.has_value());
  bool found = false;
  const Summary summary = short_run.summary({});
  for (const auto& [key, value] : summary.entries())
    if (key == "kitti_segments") {
      found = true;
      CHECK(std::get<int64_t>(value) == 0);
    } else if (key == "kitti_trans_pct") {
      CHECK(std::isnan(std::get<double>(value)));
    }
  CHECK(found);
}
