// Fuzz harness: the KITTI pose reader with and without a times.txt, and the KITTI odometry error over what it read.
// The input up to its first NUL byte is the pose file, the rest the times file (none when there is no NUL).
// Contract checked: poses or a std::runtime_error naming one of the two files; the error is a number or a refusal
// (std::invalid_argument), never a crash.
#include "eval/kitti_odometry_metric.hpp"
#include "eval/trajectory_io.hpp"
#include "temp_file.hpp"

#include <algorithm>
#include <cstdlib>
#include <stdexcept>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const uint8_t* nul = std::find(data, data + size, uint8_t{0});
  const std::string poses = sextant::fuzz::write_temp("poses.txt", data, static_cast<size_t>(nul - data));
  std::string times;
  if (nul != data + size)
    times = sextant::fuzz::write_temp("times.txt", nul + 1, static_cast<size_t>(data + size - nul - 1));
  try {
    const auto read = sextant::tools::read_kitti(poses, times);
    std::vector<sextant::engine::Pose> p;
    for (const auto& s : read) p.push_back(s.pose);
    sextant::tools::KittiMetricOptions o;
    o.lengths = {1, 2, 5};  // fuzz inputs are short runs
    o.step = 1;
    try {
      (void)sextant::tools::kitti_odometry_error(p, p, o);
    } catch (const std::invalid_argument&) {}
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    if (what.find(poses) == std::string::npos && (times.empty() || what.find(times) == std::string::npos)) std::abort();
  }
  return 0;
}
