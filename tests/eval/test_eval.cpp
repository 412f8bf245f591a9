// sextant eval reproduces the TUM benchmark tools on the real trajectories in ../shared/data/tum
// (METRICS.md §3 published value and §4 cross-check table), and the association rules on small cases.
#include "eval/trajectory_eval.hpp"

#include <doctest/doctest.h>

using namespace sextant::tools;

namespace {
std::string tum(const std::string& rel) { return std::string(SEXTANT_SHARED_DIR) + "/data/tum/" + rel; }

struct Row {
  const char* gt;
  const char* est;
  bool sim3;
  size_t matched;
  double rmse, mean, median, std, min, max;
  size_t rpe_pairs;
  double rpe_trans_rmse, rpe_trans_mean, rpe_rot_rmse, rpe_rot_mean;
};
}  // namespace

TEST_CASE("ATE and RPE equal the TUM tools' values on every trajectory of METRICS.md to 1e-6") {
  const Row rows[] = {
      {"fr2_desk/groundtruth.txt", "fr2_desk/orbslam_CameraTrajectory.txt", false, 2223, 0.008144, 0.007514, 0.007432,
       0.003140, 0.000332, 0.024329, 1998, 0.007161, 0.006502, 0.4550, 0.4016},
      {"fr1_xyz/groundtruth.txt", "fr1_xyz/rgbdslam.txt", false, 786, 0.013473, 0.012029, 0.011176, 0.006068, 0.000939,
       0.034727, 753, 0.021217, 0.019524, 0.9345, 0.8415},
      {"fr1_xyz/groundtruth.txt", "fr1_xyz/orbslam2_rgbd_CameraTrajectory.txt", false, 790, 0.009820, 0.008221,
       0.007090, 0.005372, 0.000412, 0.035857, 757, 0.015849, 0.014270, 0.9774, 0.8735},
      {"fr1_desk/groundtruth.txt", "fr1_desk/orbslam2_rgbd_CameraTrajectory.txt", false, 573, 0.016309, 0.012929,
       0.010539, 0.009941, 0.000864, 0.080453, 542, 0.022555, 0.018417, 1.3786, 1.2150},
      {"fr1_xyz/groundtruth.txt", "fr1_xyz/orbslam_mono_keyframes.txt", true, 32, 0.009755, 0.008219, 0.007909,
       0.005254, 0.001877, 0.027924, 0, 0, 0, 0, 0},
      {"fr2_desk/groundtruth.txt", "fr2_desk/orbslam_mono_keyframes.txt", true, 122, 0.007900, 0.007251, 0.007146,
       0.003134, 0.001197, 0.015766, 0, 0, 0, 0, 0},
  };
  for (const auto& r : rows) {
    CAPTURE(r.est);
    const auto gt = read_tum(tum(r.gt));
    const auto est = read_tum(tum(r.est));
    const auto ate = absolute_trajectory_error(gt, est, r.sim3);
    CHECK(ate.matched == r.matched);
    // The table prints 6 decimals: agreement to 1e-6 m means equality at that precision (half-ulp rounding).
    CHECK(std::abs(ate.error.rmse - r.rmse) <= 5e-7);
    CHECK(std::abs(ate.error.mean - r.mean) <= 5e-7);
    CHECK(std::abs(ate.error.median - r.median) <= 5e-7);
    CHECK(std::abs(ate.error.std - r.std) <= 5e-7);
    CHECK(std::abs(ate.error.min - r.min) <= 5e-7);
    CHECK(std::abs(ate.error.max - r.max) <= 5e-7);
    if (r.rpe_pairs == 0) continue;
    const auto rpe = relative_pose_error(gt, est, 1.0, DeltaUnit::kSeconds);
    CHECK(rpe.pairs == r.rpe_pairs);
    CHECK(std::abs(rpe.translation.rmse - r.rpe_trans_rmse) <= 5e-7);
    CHECK(std::abs(rpe.translation.mean - r.rpe_trans_mean) <= 5e-7);
    CHECK(std::abs(rpe.rotation_deg.rmse - r.rpe_rot_rmse) <= 5e-5);
    CHECK(std::abs(rpe.rotation_deg.mean - r.rpe_rot_mean) <= 5e-5);
  }
  // The Sim(3) scales of METRICS.md.
  CHECK(absolute_trajectory_error(read_tum(tum("fr1_xyz/groundtruth.txt")),
                                  read_tum(tum("fr1_xyz/orbslam_mono_keyframes.txt")), true)
            .scale == doctest::Approx(1.1056).epsilon(1e-4));
}

TEST_CASE("association is greedy by time difference and one to one") {
  auto at = [](std::initializer_list<double> ts) {
    std::vector<StampedPose> v;
    for (double t : ts) v.push_back({t, {}});
    return v;
  };
  // est 1.005 is closest to gt 1.0 (0.005) and would also fit gt 1.01; est 1.012 then takes gt 1.01.
  const auto m = associate(at({1.0, 1.01, 2.0}), at({1.005, 1.012, 2.5}));
  REQUIRE(m.size() == 2);
  CHECK(m[0] == std::pair<size_t, size_t>{0, 0});
  CHECK(m[1] == std::pair<size_t, size_t>{1, 1});
  CHECK(associate(at({1.0}), at({1.02})).empty());  // the window is open: |d| < 0.02
  CHECK_THROWS_WITH_AS(absolute_trajectory_error(at({1.0, 2.0}), at({5.0, 6.0})),
                       doctest::Contains("at least 2 are needed"), std::invalid_argument);
}

TEST_CASE("a perfect estimate in another frame has zero ATE, and a scaled one needs Sim(3)") {
  std::vector<StampedPose> gt, est, scaled;
  const Eigen::Quaterniond R(Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.3, 1, 0.2).normalized()));
  for (int i = 0; i < 50; ++i) {
    StampedPose p;
    p.t = i * 0.1;
    p.pose.position = {std::sin(0.3 * i), 0.1 * i, std::cos(0.2 * i)};
    gt.push_back(p);
    StampedPose q = p;
    q.pose.position = R * p.pose.position + Eigen::Vector3d(5, -2, 1);
    q.pose.orientation = R;
    est.push_back(q);
    q.pose.position *= 3.0;
    scaled.push_back(q);
  }
  CHECK(absolute_trajectory_error(gt, est).error.rmse < 1e-12);
  CHECK(absolute_trajectory_error(gt, scaled).error.rmse > 0.1);
  const auto s = absolute_trajectory_error(gt, scaled, true);
  CHECK(s.error.rmse < 1e-12);
  CHECK(s.scale == doctest::Approx(1.0 / 3.0));
}
