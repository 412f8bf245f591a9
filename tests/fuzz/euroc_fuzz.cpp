// Fuzz harness: the EuRoC converter's CSV rows.  The input up to its first NUL byte is imu0/data.csv, the rest (when
// there is a NUL) gt0/data.csv.  Contract checked: a conversion or a std::runtime_error naming one of the two files;
// what is written is every IMU sample with finite values and every ground-truth pose with a finite position and a
// unit quaternion.
#include "convert/euroc_converter.hpp"
#include "daemon/runtime/lcm_log.hpp"
#include "temp_file.hpp"

#include <sextant/imu_t.hpp>
#include <sextant/truth_t.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iterator>
#include <stdexcept>
#include <string>

using namespace sextant;

namespace {

template <class A>
bool finite(const A& a) {
  return std::all_of(std::begin(a), std::end(a), [](double x) { return std::isfinite(x); });
}

template <class Msg>
Msg decoded(const runtime::LogRecord& r) {
  Msg m;
  if (m.decode(r.data.data(), 0, static_cast<int>(r.data.size())) != static_cast<int>(r.data.size())) std::abort();
  return m;
}

void check_written(const std::string& log) {
  for (const auto& r : runtime::LogReader::read_all(log)) {
    if (r.channel == "GROUND_TRUTH") {
      const auto m = decoded<truth_t>(r);
      const double n = std::hypot(std::hypot(m.orientation[0], m.orientation[1]), m.orientation[2], m.orientation[3]);
      if (!finite(m.position) || !(std::abs(n - 1) < 1e-9)) std::abort();
    } else {
      const auto m = decoded<imu_t>(r);
      if (!finite(m.angular_velocity) || !finite(m.linear_acceleration) || !finite(m.angular_velocity_covariance) ||
          !finite(m.linear_acceleration_covariance))
        std::abort();
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  namespace fs = std::filesystem;
  static const std::string dir = [] {
    const std::string d = fuzz::temp_dir() + "/euroc";
    fs::create_directories(d + "/imu0");
    fs::create_directories(d + "/gt0");
    return d;
  }();
  const uint8_t* nul = std::find(data, data + size, uint8_t{0});
  const std::string imu = fuzz::write_temp("euroc/imu0/data.csv", data, static_cast<size_t>(nul - data));
  std::string gt = dir + "/gt0/data.csv";
  if (nul != data + size)
    fuzz::write_temp("euroc/gt0/data.csv", nul + 1, static_cast<size_t>(data + size - nul - 1));
  else
    fs::remove(gt), gt.clear();
  const std::string log = fuzz::temp_dir() + "/euroc.lcm";
  try {
    (void)tools::convert_euroc(dir, log, fuzz::temp_dir() + "/euroc_gt.txt");
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    if (what.find(imu) == std::string::npos && (gt.empty() || what.find(gt) == std::string::npos)) std::abort();
    return 0;
  }
  check_written(log);
  return 0;
}
