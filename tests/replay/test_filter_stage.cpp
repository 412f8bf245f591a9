// The filter stage on a simulated run: one EKF pose per odometry message, and a far smaller error against the
// ground truth than dead reckoning (landmark sightings correct the drift).
#include "daemon/runtime/lcm_log.hpp"
#include "replay/replay_driver.hpp"
#include "replay/simulator.hpp"
#include "replay/trajectory_eval.hpp"

#include <doctest/doctest.h>

#include <cstdio>
#include <filesystem>

using namespace sextant;

TEST_CASE("EKF-SLAM beats dead reckoning on a simulated planar run") {
  const auto log = (std::filesystem::temp_directory_path() / ("sextant_filter_" + std::to_string(::getpid()) + ".lcm")).string();
  replay::SimulationOptions o;
  o.duration_s = 60;
  o.seed = 4;
  {
    runtime::LogWriter w(log);
    replay::simulate(o, w);
  }
  config::DaemonConfig cfg;
  const auto r = replay::replay_log(log, cfg);
  CHECK(r.primary_estimator == "ekf");
  const auto& ekf = r.fused_poses.at("ekf");
  const auto& dr = r.fused_poses.at("dead_reckoning");
  CHECK(ekf.size() == dr.size());
  std::vector<replay::StampedPose> truth, e, d;
  for (const auto& t : r.truth_poses) truth.push_back({t.utime * 1e-6, t.pose});
  for (const auto& p : ekf) e.push_back({p.utime * 1e-6, p.pose});
  for (const auto& p : dr) d.push_back({p.utime * 1e-6, p.pose});
  const double ate_ekf = replay::absolute_trajectory_error(truth, e).error.rmse;
  const double ate_dr = replay::absolute_trajectory_error(truth, d).error.rmse;
  MESSAGE("ATE ekf " << ate_ekf << " m, dead reckoning " << ate_dr << " m");
  CHECK(ate_ekf < 0.5 * ate_dr);
  CHECK(ate_ekf < 0.1);
  // Published covariances are positive on x, y, yaw.
  CHECK(ekf.back().covariance(0, 0) > 0);
  CHECK(ekf.back().covariance(5, 5) > 0);
  std::remove(log.c_str());
}

TEST_CASE("landmarks without ids: JCBB association and tentative landmarks recover the map") {
  const auto log = (std::filesystem::temp_directory_path() / ("sextant_filter_unk_" + std::to_string(::getpid()) + ".lcm")).string();
  replay::SimulationOptions o;
  o.duration_s = 60;
  o.seed = 6;
  o.unknown_ids = true;
  {
    runtime::LogWriter w(log);
    replay::simulate(o, w);
  }
  config::DaemonConfig cfg;
  const auto r = replay::replay_log(log, cfg);
  std::map<std::string, int64_t> c;
  for (const auto& s : r.stages)
    if (s.name == "filter")
      for (const auto& [k, v] : s.counters) c[k] = v;
  int64_t seen_landmarks = 0;
  for (const auto& p : r.truth_points) seen_landmarks += p.kind == "landmark";
  MESSAGE("associated " << c["associated"] << ", landmarks created " << c["new_landmarks"] << " of " << seen_landmarks);
  CHECK(c["associated"] > 1000);
  CHECK(c["new_landmarks"] <= seen_landmarks);       // no duplicates or spurious permanent landmarks
  CHECK(c["new_landmarks"] >= seen_landmarks / 2);   // most of the landmarks the robot passes are mapped
  std::vector<replay::StampedPose> truth, e, d;
  for (const auto& t : r.truth_poses) truth.push_back({t.utime * 1e-6, t.pose});
  for (const auto& p : r.fused_poses.at("ekf")) e.push_back({p.utime * 1e-6, p.pose});
  for (const auto& p : r.fused_poses.at("dead_reckoning")) d.push_back({p.utime * 1e-6, p.pose});
  CHECK(replay::absolute_trajectory_error(truth, e).error.rmse < 0.5 * replay::absolute_trajectory_error(truth, d).error.rmse);
  std::remove(log.c_str());
}
