#pragma once
// The UTIAS MRCLAM data set (Leung et al., IJRR 2011, and the data set's own format description) as an LCM log,
// for one robot (convert_mrclam) or for several in one log (convert_mrclam_fleet: the robots' messages merged in time
// order).  Per robot, source "robotN":
//  - ODOMETRY: the velocity commands (v, omega) of each row integrated exactly over the time to the next row,
//    shifted later by the robots' command delay (MrclamOptions::command_delay_s),
//    Delta = Exp_SE(2)([v dt, 0, omega dt]); rows sharing a stamp are merged.  Increment covariance from a
//    distance-proportional model (see MrclamOptions).  One robot: the odometry starts at the ground-truth pose at
//    its first stamp (the odometry frame is the Vicon world frame).  A fleet: each robot's odometry starts at the
//    identity, the origin of its own frame, as a real robot's does (placing the robots is the estimator's job).
//  - LANDMARKS: the camera's range/bearing readings of one image (rows sharing a stamp) with the barcode mapped
//    to its subject id through Barcodes.dat.  Unknown barcodes are counted, not written.  Sightings of other robots
//    (subjects 1-5): one robot: counted, not written; a fleet: written as observations with id = the seen robot's
//    subject number when that robot is in the log (the fleet config's markers {N: robotN}), else counted only.
//  - GROUND_TRUTH: the robots' Vicon poses (truth_t "robot", source robotN) and the landmark map (truth_t "landmark",
//    id = subject id), plus optional text files of the ground truth (see the functions).
// Senders: one robot's messages are sent by "sextant-convert"; in a fleet log robot N's by "sextant-convert-robotN",
// so that every sender's sequence numbers per channel stay gapless in the merged log.
#include <cstdint>
#include <string>
#include <vector>

namespace sextant::tools {

struct MrclamOptions {
  // Odometry increment variances grow with the motion (Thrun et al.'s alpha model): the rows are velocity
  // commands, not encoder readings, so the robot's real motion departs from them by far more than wheel noise.
  double trans_var_per_metre = 0.01;  // m^2 per metre travelled
  double rot_var_per_radian = 0.05;   // rad^2 per radian turned
  double rot_var_per_metre = 0.05;    // rad^2 per metre travelled
  double min_sigma = 1e-4;
  // The robots carry out a velocity command about this long after its stamp: the Vicon heading rate matches the
  // commanded omega best 0.15-0.2 s later on all five robots of Dataset 7 (bench/history/2026-11-22_to_2026-11-25.md,
  // "MRCLAM SLAM").  Each command's motion is stamped this much later, so that the odometry pose at a sighting's stamp
  // is where the robot was when the camera saw it.
  double command_delay_s = 0.175;
  // Sighting noise for a filter that takes successive sightings as independent.  Against the Vicon truth (all five
  // robots, 15.8k landmark sightings) the range error is proportional to the range (sd 4.4 % of it: the camera
  // derives range from the barcode's size in pixels) and the bearing error has sd 0.015 rad; but both are strongly
  // correlated from one sighting of a landmark to the next (0.24 s apart: 0.94 for range, 0.71 for bearing; a
  // stationary robot reads the same quantized range again and again).  An AR(1) error with correlation rho
  // carries the information of white noise with variance sigma^2 (1 + rho) / (1 - rho), hence 0.044 * 5.7 and
  // 0.015 * 2.4 (bench/history/2026-11-22_to_2026-11-25.md, "MRCLAM SLAM").  With the uncorrelated 0.15 m /
  // 0.05 rad the EKF double-counted the repeated readings and became overconfident.
  double range_sigma_per_metre = 0.26;  // range sigma = this * range
  double bearing_sigma = 0.037;         // rad
};

/// Counts over all robots converted.  landmark_observations: sightings of the 15 landmarks; robot_sightings: every
/// sighting of a robot, of which robot_sightings_kept were written as observations (a fleet log only).
struct MrclamConversion {
  int64_t odometry = 0, landmark_messages = 0, landmark_observations = 0, robot_sightings = 0, robot_sightings_kept = 0,
          unknown_barcodes = 0, truth = 0;
};

/// `dir` holds Barcodes.dat, Landmark_Groundtruth.dat and RobotN_{Odometry,Measurement,Groundtruth}.dat.
/// Throws std::runtime_error naming the file and line of a malformed row.
/// One robot's log; `gt_tum` (when not empty): its ground truth as a TUM file.
MrclamConversion convert_mrclam(const std::string& dir, int robot, const std::string& out_lcm,
                                const std::string& gt_tum, const MrclamOptions& options = {});

/// Robots `robots` (each 1 to 5, no repeats) in one log, each in its own odometry frame.  With `gt_prefix` not empty:
/// each robot's ground truth as a TUM file GT_PREFIX + "robotN.txt", and the landmarks' as GT_PREFIX + "landmarks.txt"
/// (one "id x y" line per landmark, metres, Vicon world frame).
MrclamConversion convert_mrclam_fleet(const std::string& dir, const std::vector<int>& robots,
                                      const std::string& out_lcm, const std::string& gt_prefix,
                                      const MrclamOptions& options = {});

/// A robot list as written on the command line: "1-5", "1,3,5", "2-3,5".  Throws std::invalid_argument for anything
/// else, for robots outside 1-5 and for repeats.
std::vector<int> parse_mrclam_robots(const std::string& list);

}  // namespace sextant::tools
