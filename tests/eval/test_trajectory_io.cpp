// Trajectory files: KITTI poses round-trip through write_kitti / read_kitti, times come from times.txt, and every
// malformed file is refused naming its file and line.
#include "eval/trajectory_io.hpp"

#include <doctest/doctest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <stdexcept>

#include <unistd.h>

using namespace sextant::tools;

namespace {
std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("sextant_trajectory_io_" + std::to_string(::getpid()) + "_" + name))
      .string();
}
void write_text(const std::string& path, const std::string& text) { std::ofstream(path) << text; }
std::string error_of(const std::string& path, const std::string& times = "") {
  try {
    read_kitti(path, times);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST_CASE("KITTI poses round-trip through write_kitti and read_kitti") {
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0, 10);
  std::vector<StampedPose> poses;
  for (int i = 0; i < 50; ++i) {
    StampedPose s;
    s.t = i;
    s.pose.position = {n(rng), n(rng), n(rng)};
    s.pose.orientation = Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized();
    poses.push_back(s);
  }
  const std::string path = temp_path("roundtrip.txt");
  write_kitti(path, poses);
  const auto back = read_kitti(path);
  REQUIRE(back.size() == poses.size());
  for (size_t i = 0; i < poses.size(); ++i) {
    CHECK(back[i].t == static_cast<double>(i));
    CHECK((back[i].pose.position - poses[i].pose.position).norm() < 1e-7);
    CHECK(back[i].pose.orientation.angularDistance(poses[i].pose.orientation) < 1e-8);
  }
  // With the sequence's times.txt each pose gets its time.
  const std::string times = temp_path("times.txt");
  std::string text;
  for (int i = 0; i < 50; ++i) text += std::to_string(0.1 * i + 3) + "\n";
  write_text(times, text);
  const auto timed = read_kitti(path, times);
  CHECK(timed[0].t == doctest::Approx(3.0));
  CHECK(timed[49].t == doctest::Approx(7.9));
  std::remove(path.c_str());
  std::remove(times.c_str());
}

TEST_CASE("read_kitti names the file and line of what it cannot read") {
  const std::string path = temp_path("bad.txt");
  const std::string identity = "1 0 0 0 0 1 0 0 0 0 1 0\n";
  write_text(path, identity + "1 0 0 0 0 1 0 0 0 0 1\n");
  CHECK(error_of(path).find(path + ":2: expected 12 values") != std::string::npos);
  write_text(path, identity + "\n1 0 0 0 0 1 0 0 0 0 1 x\n");
  CHECK(error_of(path).find(path + ":3: not a number: 'x'") != std::string::npos);
  write_text(path, "1 0 0 0 0 1 0 0 0 0 1 nan\n");
  CHECK(error_of(path).find(path + ":1: value 12 is not finite") != std::string::npos);
  // A TUM row with 4 more numbers, and a matrix that is not a rotation (scaled, and a reflection).
  write_text(path, "2 0 0 0 0 2 0 0 0 0 2 0\n");
  CHECK(error_of(path).find(path + ":1: the 3x3 block is not a rotation") != std::string::npos);
  write_text(path, "-1 0 0 0 0 1 0 0 0 0 1 0\n");
  CHECK(error_of(path).find(path + ":1: the 3x3 block is not a rotation") != std::string::npos);
  // times.txt: fewer, more, not increasing.
  const std::string times = temp_path("bad_times.txt");
  write_text(path, identity + identity);
  write_text(times, "0.0\n");
  CHECK(error_of(path, times).find(times + ": 1 times for the 2 poses of " + path) != std::string::npos);
  write_text(times, "0.0\n0.1\n0.2\n");
  CHECK(error_of(path, times).find(times + ":3: more times than the 2 poses") != std::string::npos);
  write_text(times, "0.5\n0.5\n");
  CHECK(error_of(path, times).find(times + ":2: time") != std::string::npos);
  CHECK(error_of(temp_path("missing.txt")).find("cannot read") != std::string::npos);
  std::remove(path.c_str());
  std::remove(times.c_str());
}
