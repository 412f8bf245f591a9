#pragma once
// `sextant simulate`: a synthetic field run with its ground truth, written as an LCM log in utime order.
//
// A robot drives laps of a closed "stadium" course (two straight sides joined by half circles) at constant speed;
// in the `spatial` scenario it also climbs and descends (height, pitch and a small roll vary along the course).
//  - ODOMETRY (odometry_t): the composition of noisy increments Delta_k = Delta_true_k * exp(eta_k),
//    eta ~ N(0, Q_k) with Q_k proportional to the distance travelled; covariance propagated to first order
//    (the same right-perturbation propagation dead reckoning uses) and the increment covariance Q_k.
//  - LANDMARKS (landmarks_t): point landmarks within range and field of view, as range/azimuth(/elevation) with
//    Gaussian noise; ids known, or -1 with `unknown_ids`.
//  - BEARINGS (bearing_scan_t): static passive sensors observing slowly moving targets: azimuth/elevation with
//    Gaussian noise, detection probability p_detect, Poisson false alarms (anywhere, or in each sensor's field of
//    view over a surveillance box); one scan_id per round across sensors, detections shuffled so their order carries
//    no information.
//  - LOOP_CLOSURES (loop_closure_t): when the robot comes back within `loop_distance` of a pose at least
//    `loop_min_age_s` old, the true relative pose plus noise, with the matching information matrix.
//  - IMU (imu_t) and GNSS (gnss_t), when their rates are positive: the robot's IMU (white noise, bias random walk,
//    mounting) and GNSS receiver (noise, periodic outages, multipath outliers, fixes in latitude/longitude/altitude
//    around `gnss.datum`), from the same true trajectory (sim/inertial_sensor_sim.hpp), with their own random
//    stream so that the other streams do not change when they are switched on.
//  - GROUND_TRUTH (truth_t): robot poses at the odometry rate, target positions per scan, landmarks once.
// A fleet (`robots` > 1): robots robot1..robotN (sources), robot i (0-based) driving the course rotated by i pi / N
// about the origin (the courses cross), all at t = 0 at their courses' start, in one world of shared landmarks (drawn
// over [-24, 24] m in x and y instead); the odometry and landmark sightings as above, each robot's odometry starting at
// the identity (its own frame; the robots' relative placement is unknown to the estimator), and:
//  - robot sightings: in each robot's LANDMARKS message, the range/azimuth(/elevation) of every other robot's origin
//    within range and field of view, with the landmarks' noise, id = that robot's marker 1000000 + N for robotN (no
//    landmark id reaches it; the markers are also the `id` of the robots' truth_t, and `sextant simulate
//    --config-out` writes them as the config's engine.graph.fleet.markers);
//  - inter-robot loop closures: when a robot comes within `loop_distance` of the latest pose another robot had in
//    that part of the world (a grid of loop_distance cells, the 3 x 3 around it), at most one per
//    `loop_min_interval_s` per robot: source = the other robot ("from", its pose then), source_to = the robot
//    ("to", now), relative = T_from^-1 T_to with the loops' noise.  A share `wrong_loops` of them is wrong: the
//    relative pose composed with a random offset of 3-10 m and any heading (drawn independently per loop).
// IMU and GNSS are simulated for one robot only.
// Deterministic for a seed: the same options give a byte-identical log.
#include "daemon/engine/events.hpp"
#include "daemon/runtime/lcm_log.hpp"
#include "eval/trajectory_io.hpp"
#include "sim/inertial_sensor_sim.hpp"

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace sextant::tools {

/// The simulated world: a planar robot (x, y, yaw) or one that also climbs, pitches and rolls (3-D).
enum class Scenario { kPlanar, kSpatial };
/// The scenario spelt "planar" or "spatial"; throws std::invalid_argument naming the spellings for any other name.
Scenario scenario_from_name(const std::string& name);
const char* scenario_name(Scenario scenario);
std::vector<std::string> scenario_names();

struct SimulationOptions {
  Scenario scenario = Scenario::kPlanar;
  uint64_t seed = 1;
  double duration_s = 60;
  int64_t start_utime = 1'700'000'000'000'000;  // 2023-11-14, an arbitrary fixed epoch
  std::string source = "robot1";                // one robot's name (a fleet's are robot1..robotN)
  int robots = 1;                               // more than 1: a fleet (above)
  double wrong_loops = 0;                       // fleet: share of the inter-robot loop closures that are wrong, 0..1
  /// fleet: the wrong loops are drawn as above but not written (their sequence numbers skipped, as if lost); every
  /// other message is the same, byte for byte, as with them (the same draws are made): the run "without the wrong
  /// loops" of the same realization, to which the run with them compares (a run with a share of 0 differs in every
  /// noise draw after the first wrong loop).
  bool omit_wrong_loops = false;

  // Robot and odometry.
  double speed = 2.0;  // m/s along the course
  double odometry_rate_hz = 50;
  double odometry_trans_noise = 0.02;  // standard deviation per metre travelled, m/m (per axis)
  double odometry_rot_noise = 0.01;    // standard deviation per metre travelled, rad/m (per axis)
  double odometry_min_sigma = 1e-4;    // floor on every increment standard deviation

  // Landmarks.
  int landmarks = 40;
  double landmark_rate_hz = 10;
  double landmark_max_range = 12;
  double landmark_fov = 3.14159265358979323846;     // total horizontal field of view, rad (centred ahead)
  double range_sigma = 0.05, bearing_sigma = 0.01;  // m, rad
  bool unknown_ids = false;

  // Passive sensors and targets.
  int sensors = 4;
  int targets = 4;
  double scan_rate_hz = 2;
  double bearing_sensor_sigma = 0.005;  // rad (5 mrad)
  double p_detect = 0.9;
  double clutter = 1.0;  // mean false alarms per sensor per scan
  // Where the false alarms are drawn.  Empty (default): uniform over all azimuths and elevations 0..0.8 rad, mostly
  // far from every target's direction.  A box [clutter_region_min, clutter_region_max] (world frame, m, 3 numbers
  // each): uniform in each sensor's field of view over that box padded by 5 bearing sigmas (assoc/field_of_view.hpp),
  // as `sextant assoc-sim` draws them, so they compete with the targets' detections and the daemon's
  // `association.region_min/max` + `false_alarms_per_scan` (same box, same count) state the true clutter density.
  std::vector<double> clutter_region_min, clutter_region_max;

  // Loop closures.
  double loop_distance = 2.0;      // m
  double loop_min_age_s = 20;      // s
  double loop_min_interval_s = 1;  // s between two loop closures
  double loop_trans_sigma = 0.05, loop_rot_sigma = 0.01;

  // IMU and GNSS (0 Hz: not simulated).  imu.rate_hz and gnss.rate_hz are set from these.
  double imu_rate_hz = 0, gnss_rate_hz = 0;
  SimulatedImuOptions imu;
  SimulatedGnssOptions gnss;
};

/// The marker id of robot N (1-based) of a fleet: its sightings by the other robots carry this id.
constexpr int64_t fleet_marker(int robot) { return 1'000'000 + robot; }

struct SimulationSummary {
  int64_t odometry = 0, landmark_messages = 0, landmark_observations = 0, bearing_scans = 0, detections = 0,
          false_alarms = 0, loop_closures = 0, truth = 0, imu = 0, gnss = 0, gnss_outliers = 0;
  int64_t robot_sightings = 0, inter_robot_loops = 0, wrong_loops = 0;  // a fleet's (landmark_observations
                                                                        // counts the landmarks' only; wrong loops
                                                                        // omitted count in wrong_loops only)
  std::vector<std::pair<int64_t, engine::Pose>> robot_truth;  // (utime, pose), at the odometry rate (the first robot)
  std::map<std::string, std::vector<std::pair<int64_t, engine::Pose>>> fleet_truth;  // every robot's, by source
  std::map<int64_t, std::string> markers;                                            // a fleet's marker ids -> sources
  LandmarkPositions landmarks;  // the landmarks' true positions, by id
};

/// Writes the run into `out`; throws std::invalid_argument for bad options.
SimulationSummary simulate(const SimulationOptions& options, runtime::LogWriter& out);

}  // namespace sextant::tools
