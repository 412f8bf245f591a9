#pragma once
// The UTIAS MRCLAM data set (Leung et al., IJRR 2011, and the data set's own format description) as an LCM log
// for one robot:
//  - ODOMETRY: the velocity commands (v, omega) of each row integrated exactly over the time to the next row,
//    shifted later by the robots' command delay (MrclamOptions::command_delay_s),
//    Delta = Exp_SE(2)([v dt, 0, omega dt]), starting from the ground-truth pose at the first odometry stamp (so the
//    odometry frame is the Vicon world frame); rows sharing a stamp are merged.  Increment covariance from a
//    distance-proportional model (see MrclamOptions).
//  - LANDMARKS: the camera's range/bearing readings of one image (rows sharing a stamp) with the barcode mapped
//    to its subject id through Barcodes.dat; sightings of other robots (subjects 1-5) and unknown barcodes are not
//    landmarks and are counted, not written.
//  - GROUND_TRUTH: the robot's Vicon poses (truth_t "robot") and the landmark map (truth_t "landmark", id =
//    subject id), plus an optional TUM file of the robot's ground truth.
#include <cstdint>
#include <string>

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

struct MrclamConversion {
  int64_t odometry = 0, landmark_messages = 0, landmark_observations = 0, robot_sightings = 0, unknown_barcodes = 0,
          truth = 0;
};

/// `dir` holds Barcodes.dat, Landmark_Groundtruth.dat and RobotN_{Odometry,Measurement,Groundtruth}.dat.
/// Throws std::runtime_error naming the file and line of a malformed row.
MrclamConversion convert_mrclam(const std::string& dir, int robot, const std::string& out_lcm,
                                const std::string& gt_tum, const MrclamOptions& options = {});

}  // namespace sextant::tools
