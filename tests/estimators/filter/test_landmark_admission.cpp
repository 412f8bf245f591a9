// EKF-SLAM's admission of a new landmark (landmark_admission.hpp), on its own and through the planar and the 3-D
// EKF: only in SLAM mode, only with an id, only below max_landmarks; a refused sighting leaves the state as it was.
#include "estimators/filter/landmark_admission.hpp"
#include "estimators/filter/planar_ekf.hpp"
#include "estimators/filter/spatial_ekf.hpp"

#include <doctest/doctest.h>

#include <string>

using namespace sextant;
using namespace sextant::filter;

TEST_CASE("admit_new_landmark: the rule's three outcomes, and the state grows only when it says new_landmark") {
  int added = 0;
  const auto add = [&] { ++added; };
  CHECK(admit_new_landmark(false, 7, 0, 10, add).reason == UpdateReason::kUnknownLandmark);
  CHECK(admit_new_landmark(true, -1, 0, 10, add).reason == UpdateReason::kUnknownLandmark);
  CHECK(admit_new_landmark(true, 7, 10, 10, add).reason == UpdateReason::kMapFull);
  CHECK(admit_new_landmark(true, 7, 11, 10, add).reason == UpdateReason::kMapFull);
  CHECK(added == 0);
  const UpdateResult r = admit_new_landmark(true, 7, 9, 10, add);
  CHECK(r.accepted);
  CHECK(r.reason == UpdateReason::kNewLandmark);
  CHECK(added == 1);
  CHECK_FALSE(admit_new_landmark(false, 7, 0, 10, add).accepted);
  // The spellings counters and logs use.
  CHECK(std::string(update_reason_name(UpdateReason::kNewLandmark)) == "new_landmark");
  CHECK(std::string(update_reason_name(UpdateReason::kUnknownLandmark)) == "unknown_landmark");
  CHECK(std::string(update_reason_name(UpdateReason::kMapFull)) == "map_full");
  CHECK(std::string(update_reason_name(UpdateReason::kGate)) == "gate");
}

TEST_CASE("planar and 3-D EKF: the second new landmark past max_landmarks = 1 is refused and the state is unchanged") {
  PlanarEkfOptions po;
  po.max_landmarks = 1;
  PlanarEkf planar(po);
  planar.initialize(SE2(0, 0, 0), Eigen::Matrix3d::Identity() * 1e-4);
  const Eigen::Matrix2d R2 = Eigen::Vector2d(0.01, 0.001).asDiagonal();
  CHECK(planar.observe(1, 2.0, 0.3, R2).reason == UpdateReason::kNewLandmark);
  const Eigen::MatrixXd P_before = planar.covariance();
  const UpdateResult full = planar.observe(2, 3.0, -0.2, R2);
  CHECK_FALSE(full.accepted);
  CHECK(full.reason == UpdateReason::kMapFull);
  CHECK(planar.landmark_count() == 1);
  CHECK(planar.covariance() == P_before);
  CHECK(planar.observe(-1, 3.0, -0.2, R2).reason == UpdateReason::kUnknownLandmark);

  SpatialEkfOptions so;
  so.max_landmarks = 1;
  SpatialEkf spatial(so);
  spatial.initialize(SE3(), SE3::Matrix6::Identity() * 1e-4);
  const Eigen::Matrix3d R3 = Eigen::Vector3d(0.01, 0.001, 0.001).asDiagonal();
  CHECK(spatial.observe(1, Eigen::Vector3d(2, 0.3, 0.1), R3).reason == UpdateReason::kNewLandmark);
  const UpdateResult full3 = spatial.observe(2, Eigen::Vector3d(3, -0.2, 0.05), R3);
  CHECK(full3.reason == UpdateReason::kMapFull);
  CHECK(spatial.landmark_count() == 1);
  so.slam = false;
  SpatialEkf no_slam(so);
  no_slam.initialize(SE3(), SE3::Matrix6::Identity() * 1e-4);
  CHECK(no_slam.observe(1, Eigen::Vector3d(2, 0.3, 0.1), R3).reason == UpdateReason::kUnknownLandmark);
  CHECK(no_slam.landmark_count() == 0);
}
