// EKF consistency on simulated runs: the pose NEES averaged over several seeds stays inside the 95 % chi-square
// bounds, for localization against a known map and for EKF-SLAM (sim/filter_consistency.hpp).
#include "sim/filter_consistency.hpp"

#include <doctest/doctest.h>

using namespace sextant;

namespace {

tools::ConsistencyOptions short_runs(bool slam) {
  tools::ConsistencyOptions o;
  o.runs = 8;
  o.slam = slam;
  o.simulation.duration_s = 30;
  o.every = 25;                      // 2 samples per second
  o.filter.initial_sigma_xy = 1e-3;  // the simulator's first odometry pose is exact to about 1 mm
  o.filter.initial_sigma_theta = 1e-3;
  return o;
}

}  // namespace

TEST_CASE("EKF localization with a known map is consistent: average pose NEES inside the 95 % bounds") {
  const auto r = tools::pose_nees_over_runs(short_runs(false));
  MESSAGE("localization: mean ANEES " << r.mean_anees << " in [" << r.lower << ", " << r.upper << "], "
                                      << 100 * r.fraction_inside << " % of samples inside, final position RMSE "
                                      << r.final_position_rmse);
  CHECK(r.mean_anees > r.lower);
  CHECK(r.mean_anees < r.upper);
  CHECK(r.fraction_inside > 0.85);
}

TEST_CASE("EKF-SLAM is consistent on short runs: average pose NEES inside the 95 % bounds") {
  const auto r = tools::pose_nees_over_runs(short_runs(true));
  MESSAGE("SLAM: mean ANEES " << r.mean_anees << " in [" << r.lower << ", " << r.upper << "], "
                              << 100 * r.fraction_inside << " % of samples inside, final position RMSE "
                              << r.final_position_rmse);
  CHECK(r.mean_anees > r.lower);
  CHECK(r.mean_anees < r.upper);
  CHECK(r.fraction_inside > 0.85);
}

TEST_CASE("3-D EKF-SLAM pose NEES (6 dof) over seeds") {
  auto o = short_runs(true);
  o.simulation.scenario = tools::Scenario::kSpatial;
  const auto r = tools::pose_nees_over_runs(o);
  MESSAGE("3-D SLAM: mean ANEES " << r.mean_anees << " in [" << r.lower << ", " << r.upper << "], "
                                  << 100 * r.fraction_inside << " % of samples inside, final position RMSE "
                                  << r.final_position_rmse);
  CHECK(r.mean_anees > r.lower);
  CHECK(r.mean_anees < r.upper);
}
