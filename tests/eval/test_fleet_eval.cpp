// The fleet evaluation on synthetic fleets: an estimate that is the truth moved by one rigid transform has no error
// under the fleet's one alignment; a robot whose frame alone is shifted shows its shift in the fleet frame and none
// under its own alignment.
#include "eval/fleet_eval.hpp"

#include <doctest/doctest.h>

#include <cmath>

using namespace sextant::tools;

namespace {

sextant::engine::Pose planar_pose(double x, double y, double yaw) {
  sextant::engine::Pose p;
  p.position = {x, y, 0};
  p.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()));
  return p;
}

// Robot i drives a circle of radius 2 + i around (3 i, -i), one pose every 0.1 s for 60 s.
std::map<std::string, std::vector<StampedPose>> fleet_truth(int robots, int poses = 600) {
  std::map<std::string, std::vector<StampedPose>> out;
  for (int i = 0; i < robots; ++i)
    for (int k = 0; k < poses; ++k) {
      const double t = 100 + 0.1 * k, a = 0.05 * k, r = 2 + i;
      out["robot" + std::to_string(i + 1)].push_back(
          {t, planar_pose(3 * i + r * std::cos(a), -i + r * std::sin(a), a + M_PI / 2)});
    }
  return out;
}

LandmarkPositions landmark_truth() {
  LandmarkPositions l;
  for (int id = 0; id < 12; ++id) l[id] = Eigen::Vector3d(-5 + id, 4 * std::sin(id), 0);
  return l;
}

// x -> T x for a planar T = (yaw, tx, ty).
Eigen::Vector3d moved(const Eigen::Vector3d& p, double yaw, double tx, double ty) {
  return Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * p + Eigen::Vector3d(tx, ty, 0);
}

}  // namespace

TEST_CASE("fleet evaluation: a rigid transform of the whole fleet's truth has zero error under one alignment") {
  const auto truth = fleet_truth(3);
  const auto lm_truth = landmark_truth();
  auto est = truth;
  for (auto& [body, poses] : est)
    for (auto& p : poses) p.pose.position = moved(p.pose.position, 0.7, -4, 2.5);
  LandmarkPositions lm;
  for (const auto& [id, p] : lm_truth) lm[id] = moved(p, 0.7, -4, 2.5);
  lm[99] = Eigen::Vector3d(1, 1, 0);  // no ground truth: left out of the alignment
  const auto e = evaluate_fleet(est, lm, truth, lm_truth);
  REQUIRE(e.robots.size() == 3);
  for (const auto& [body, r] : e.robots) {
    CAPTURE(body);
    CHECK(r.matched == 600);
    CHECK(r.fleet.rmse < 1e-9);
    CHECK(r.own.rmse < 1e-9);
  }
  CHECK(e.landmarks.count == 12);
  CHECK(e.landmarks_estimated == 13);
  CHECK(e.landmarks.rmse < 1e-9);
  // The alignment is the inverse of the transform applied.
  CHECK(std::atan2(e.alignment.rotation(1, 0), e.alignment.rotation(0, 0)) == doctest::Approx(-0.7));
  CHECK(e.alignment(moved(Eigen::Vector3d(1, 2, 0), 0.7, -4, 2.5)).isApprox(Eigen::Vector3d(1, 2, 0), 1e-9));
}

TEST_CASE("fleet evaluation: a robot in a shifted frame shows its shift under the fleet's alignment only") {
  // Robot 3 has few poses next to the others and the landmarks, so the joint alignment barely follows it.
  auto truth = fleet_truth(3);
  truth["robot3"].resize(20);
  const auto lm_truth = landmark_truth();
  auto est = truth;
  for (auto& p : est["robot3"]) p.pose.position += Eigen::Vector3d(0.3, -0.4, 0);  // a 0.5 m shift
  const auto e = evaluate_fleet(est, lm_truth, truth, lm_truth);
  REQUIRE(e.robots.count("robot3"));
  CHECK(e.robots.at("robot3").fleet.rmse == doctest::Approx(0.5).epsilon(0.03));
  CHECK(e.robots.at("robot3").own.rmse < 1e-9);
  CHECK(e.robots.at("robot1").fleet.rmse < 0.05);
  CHECK(e.landmarks.rmse < 0.05);
  // A robot without ground truth is left out; nothing matching at all is an error.
  est["robot9"] = est["robot1"];
  CHECK(evaluate_fleet(est, lm_truth, truth, lm_truth).robots.count("robot9") == 0);
  CHECK_THROWS_AS(evaluate_fleet({}, {}, truth, lm_truth), std::invalid_argument);
}

TEST_CASE("align_points: planar alignment is SE(2), from x and y only") {
  Eigen::Matrix3Xd model(3, 4), data(3, 4);
  model << 0, 1, 0, 2, 0, 0, 1, 3, 5, -2, 0, 1;  // z of the model ignored
  for (int k = 0; k < 4; ++k) {
    data.col(k) = moved(Eigen::Vector3d(model(0, k), model(1, k), 0), -1.2, 0.5, 0.25);
  }
  const auto a = align_points(model, data, false, true);
  CHECK(a.rotation(2, 2) == 1.0);
  CHECK(a.translation.z() == 0.0);
  CHECK(std::atan2(a.rotation(1, 0), a.rotation(0, 0)) == doctest::Approx(-1.2));
  CHECK(a.translation.x() == doctest::Approx(0.5));
  CHECK(a.translation.y() == doctest::Approx(0.25));
  CHECK_THROWS_AS(align_points(model.leftCols(1), data.leftCols(1)), std::invalid_argument);
}
