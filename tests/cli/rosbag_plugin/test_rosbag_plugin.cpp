// `sextant convert rosbag` through its module: `sextant` itself starts without ROS's libraries, the module writes
// byte for byte the log the converter writes in-process, and a missing module is a clear error, not a crash.
#include "convert/rosbag/rosbag_converter.hpp"

#include <doctest/doctest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace {

struct Output {
  int status = -1;   // the exit status
  std::string text;  // standard output and error
};

Output run(const std::string& command) {
  Output o;
  FILE* p = popen((command + " 2>&1").c_str(), "r");
  REQUIRE(p != nullptr);
  char buf[4096];
  for (size_t n; (n = std::fread(buf, 1, sizeof buf, p)) > 0;) o.text.append(buf, n);
  const int s = pclose(p);
  o.status = WIFEXITED(s) ? WEXITSTATUS(s) : -1;
  return o;
}

std::string bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

const std::string kSextant = std::string(SEXTANT_BIN_DIR) + "/sextant";
const std::string kBag = std::string(SEXTANT_SHARED_DIR) + "/data/inertial/robot_localization_bag1/test1.bag";

}  // namespace

TEST_CASE("rosbag module: sextant loads none of ROS's libraries at start-up") {
  const Output ldd = run("ldd " + kSextant);
  REQUIRE(ldd.status == 0);
  CHECK(ldd.text.find("libcholmod") != std::string::npos);  // what optimize needs is there
  CHECK(ldd.text.find("librosbag_storage") == std::string::npos);
  CHECK(ldd.text.find("libroslib") == std::string::npos);
  CHECK(ldd.text.find("libpython") == std::string::npos);
}

TEST_CASE("rosbag module: sextant convert rosbag writes the log the in-process converter writes") {
  const auto dir = std::filesystem::temp_directory_path() / ("sextant_rosbag_module_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string via_module = (dir / "module.lcm").string(), in_process = (dir / "direct.lcm").string();
  const Output o =
      run(kSextant + " convert rosbag " + kBag + " --frame base_link=husky --frame imu_link=husky -o " + via_module);
  REQUIRE_MESSAGE(o.status == 0, o.text);
  CHECK(o.text.find("IMU 11865") != std::string::npos);
  sextant::tools::RosbagConversionOptions conv;
  conv.bodies = {{"base_link", "husky"}, {"imu_link", "husky"}};
  const auto c = sextant::tools::convert_rosbag(kBag, in_process, conv);
  CHECK(c.written.at("IMU") == 11865);
  const std::string a = bytes(via_module), b = bytes(in_process);
  CHECK(a.size() > 100000);
  CHECK(a == b);
  std::filesystem::remove_all(dir);
}

TEST_CASE("rosbag module: a sextant without its module says so and exits 2") {
  const auto dir = std::filesystem::temp_directory_path() / ("sextant_no_module_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir / "bin");
  std::filesystem::copy_file(kSextant, dir / "bin" / "sextant");
  std::filesystem::permissions(dir / "bin" / "sextant", std::filesystem::perms::owner_exec,
                               std::filesystem::perm_options::add);
  const Output o =
      run((dir / "bin" / "sextant").string() + " convert rosbag " + kBag + " -o " + (dir / "out.lcm").string());
  CHECK(o.status == 2);
  CHECK(o.text.find("cannot load the rosbag module") != std::string::npos);
  CHECK(o.text.find("libsextant_rosbag.so") != std::string::npos);
  // The other subcommands still run.
  CHECK(run((dir / "bin" / "sextant").string() + " --version").status == 0);
  std::filesystem::remove_all(dir);
}
