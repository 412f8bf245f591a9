// The EuRoC converter on hand-written folders: a ground-truth quaternion far from unit length is the rotation it
// spells, one of zeros is refused by file and line, and stamps at int64's ends convert (their span overflows int64).
#include "convert/euroc_converter.hpp"
#include "daemon/runtime/lcm_log.hpp"

#include <unistd.h>

#include <doctest/doctest.h>

#include <sextant/imu_t.hpp>
#include <sextant/truth_t.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

using namespace sextant;

namespace {

// A EuRoC folder of two IMU rows and one ground-truth row with quaternion `q` (w x y z).
std::string folder(const std::string& name, const std::string& t0, const std::string& t1, const std::string& q) {
  const auto dir = std::filesystem::temp_directory_path() / ("sextant_euroc_" + std::to_string(::getpid()) + name);
  std::filesystem::create_directories(dir / "imu0");
  std::filesystem::create_directories(dir / "gt0");
  std::ofstream(dir / "imu0/data.csv") << "#timestamp,wx,wy,wz,ax,ay,az\n"
                                       << t0 << ",0,0,0.1,0,0,9.81\n"
                                       << t1 << ",0,0,0.1,0,0,9.81\n";
  std::ofstream(dir / "gt0/data.csv") << "#timestamp,p,q,v,bw,ba\n" << t0 << ",1,2,3," << q << ",0,0,0,0,0,0,0,0,0\n";
  return dir.string();
}

}  // namespace

TEST_CASE("EuRoC: a ground-truth quaternion of 1e300s or denormals is a rotation, one of zeros is named by line") {
  for (const char* q : {"1e300,0,0,1e300", "5e-324,0,0,5e-324"}) {
    CAPTURE(q);
    const auto dir = folder("q", "1000000", "6000000", q);
    const auto log = dir + "/out.lcm";
    const auto r = tools::convert_euroc(dir, log);
    CHECK(r.truth == 1);
    for (const auto& e : runtime::LogReader::read_all(log)) {
      if (e.channel != "GROUND_TRUTH") continue;
      truth_t m;
      REQUIRE(m.decode(e.data.data(), 0, static_cast<int>(e.data.size())) == static_cast<int>(e.data.size()));
      CHECK(m.orientation[0] == doctest::Approx(std::sqrt(0.5)));
      CHECK(m.orientation[3] == doctest::Approx(std::sqrt(0.5)));
    }
    std::filesystem::remove_all(dir);
  }
  const auto dir = folder("z", "1000000", "6000000", "0,0,0,0");
  CHECK_THROWS_WITH_AS(tools::convert_euroc(dir, dir + "/out.lcm"),
                       doctest::Contains("gt0/data.csv:2: the orientation quaternion is zero"), std::runtime_error);
  std::filesystem::remove_all(dir);
}

TEST_CASE("EuRoC: stamps at int64's ends convert with a finite rate, and one beyond them is named by line") {
  const auto dir = folder("s", "-9223372036854775808", "9223372036854775807", "1,0,0,0");
  const auto log = dir + "/out.lcm";
  CHECK(tools::convert_euroc(dir, log).imu == 2);
  for (const auto& e : runtime::LogReader::read_all(log)) {
    if (e.channel != "IMU") continue;
    imu_t m;
    REQUIRE(m.decode(e.data.data(), 0, static_cast<int>(e.data.size())) == static_cast<int>(e.data.size()));
    CHECK(std::isfinite(m.angular_velocity_covariance[0]));
    CHECK(m.angular_velocity_covariance[0] > 0);
  }
  std::filesystem::remove_all(dir);
  const auto far = folder("f", "1000000", "9223372036854775808", "1,0,0,0");
  CHECK_THROWS_WITH_AS(tools::convert_euroc(far, far + "/out.lcm"),
                       doctest::Contains("imu0/data.csv:3: timestamp out of range"), std::runtime_error);
  std::filesystem::remove_all(far);
}
