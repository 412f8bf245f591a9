#pragma once
// EuRoC MAV data set folders (Burri et al., IJRR 2016; the ASL CSV layout) -> an LCM log of imu_t samples with the
// ground truth.
//
// Input, in DIR or DIR/mav0: imu0/data.csv (timestamp [ns], w_RS_S_x..z [rad/s], a_RS_S_x..z [m/s^2]) and, when
// present, the ground truth state_groundtruth_estimate0/data.csv or gt0/data.csv (timestamp [ns], p_RS_R [m],
// q_RS [w x y z], v_RS_R [m/s], b_w_RS_S [rad/s], b_a_RS_S [m/s^2]).  Lines starting with '#' are headers.
// Output: imu_t on `imu_channel` (source `source`, frame "imu0"; angular velocity and specific force as measured,
// no orientation; covariances the discrete white-noise variances density^2 * rate of the data set's ADIS16448, at
// the rate measured from the file) and truth_t (kind "robot") on GROUND_TRUTH, written in time order (utime =
// timestamp / 1000).  `gt_tum`: the ground truth also as a TUM trajectory.
#include <cstdint>
#include <string>

namespace sextant::tools {

struct EurocConversionOptions {
  std::string source = "mav";
  std::string imu_channel = "IMU";
  double gyro_noise_density = 1.6968e-4;  // rad/s/sqrt(Hz), EuRoC's imu0/sensor.yaml
  double accel_noise_density = 2.0e-3;    // m/s^2/sqrt(Hz)
};

struct EurocConversion {
  int64_t imu = 0;
  int64_t truth = 0;
};

/// Throws std::runtime_error naming the file and line of a malformed row (wrong column count, a number that does
/// not parse or is not finite, a timestamp out of int64's range or not after the previous one, a ground-truth
/// quaternion of zeros), or a folder without imu0/data.csv.
EurocConversion convert_euroc(const std::string& dir, const std::string& out_lcm, const std::string& gt_tum = "",
                              const EurocConversionOptions& options = {});

}  // namespace sextant::tools
