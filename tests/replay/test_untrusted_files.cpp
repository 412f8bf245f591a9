// Readers of files from outside (TUM, MRCLAM, LCM logs through replay; g2o's: tests/estimators/graph/test_g2o_io.cpp)
// on the inputs that used to loop, cast out of range (undefined behaviour) or stop silently: each now ends with a
// clear error naming FILE:LINE, or reads on.
#include "daemon/config/daemon_config.hpp"
#include "daemon/runtime/lcm_log.hpp"
#include "convert/mrclam_converter.hpp"
#include "replay/replay_driver.hpp"
#include "sim/simulator.hpp"
#include "convert/tum_converter.hpp"

#include <doctest/doctest.h>

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>

using namespace sextant;

namespace {
std::string temp(const std::string& n) {
  return (std::filesystem::temp_directory_path() / ("sextant_untrusted_" + std::to_string(::getpid()) + "_" + n))
      .string();
}
}  // namespace

TEST_CASE("TUM -> LCM: a 9e12-second gap converts at once (frame-time stepping looped ~10^14 times)") {
  const auto gt = temp("gap.txt"), log = temp("gap.lcm");
  std::ofstream(gt) << "1.0 0 0 0 0 0 0 1\n1.05 0.01 0 0 0 0 0 1\n9e12 1 0 0 0 0 0 1\n9e12 1 0 0 0 0 0 1\n";
  const auto t0 = std::chrono::steady_clock::now();
  tools::TumConversionOptions o;
  o.frame_rate_hz = 30;
  const auto r = tools::convert_tum(gt, log, o);
  CHECK(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() < 5.0);
  CHECK(r.odometry == 3);
  std::ofstream(gt) << "1.0 0 0 0 0 0 0 1\n1e300 1 0 0 0 0 0 1\n";
  CHECK_THROWS_WITH(tools::convert_tum(gt, log, o), doctest::Contains((gt + ":2: timestamp").c_str()));
  std::ofstream(gt) << "1.0 0 0 0 0 0 0 1\nnan 1 0 0 0 0 0 1\n";
  CHECK_THROWS_WITH(tools::convert_tum(gt, log, o), doctest::Contains((gt + ":2: value 1 is not finite").c_str()));
  std::remove(gt.c_str());
  std::remove(log.c_str());
}

TEST_CASE("MRCLAM: a barcode or landmark id outside int's range is an error naming FILE:LINE (it became landmark 6)") {
  const auto dir = temp("mrclam");
  std::filesystem::create_directories(dir);
  const std::string hdr = "#\n#\n#\n#\n";
  auto write = [&](const std::string& name, const std::string& body) {
    std::ofstream(dir + "/" + name) << hdr << body;
  };
  write("Barcodes.dat", "6 27\n7 1e11\n");
  write("Landmark_Groundtruth.dat", "6 1.0 2.0 0.01 0.01\n");
  write("Robot1_Groundtruth.dat", "1.0 0 0 0\n1.1 0.01 0 0\n");
  write("Robot1_Odometry.dat", "1.0 0.1 0\n1.1 0.1 0\n");
  write("Robot1_Measurement.dat", "1.05 27 2.0 0.5\n");
  CHECK_THROWS_WITH(tools::convert_mrclam(dir, 1, dir + "/out.lcm", ""),
                    doctest::Contains((dir + "/Barcodes.dat:6: not an integer in int's range").c_str()));
  write("Barcodes.dat", "6 27\n");
  write("Robot1_Measurement.dat", "1.05 27 2.0 0.5\n1.07 4.5 2.0 0.5\n");
  CHECK_THROWS_WITH(tools::convert_mrclam(dir, 1, dir + "/out.lcm", ""),
                    doctest::Contains((dir + "/Robot1_Measurement.dat:6: not an integer").c_str()));
  write("Robot1_Measurement.dat", "1.05 27 2.0 0.5\n");
  CHECK_NOTHROW(tools::convert_mrclam(dir, 1, dir + "/out.lcm", ""));
  std::filesystem::remove_all(dir);
}

TEST_CASE("replay of a log with a corrupt event mid-file replays the rest and reports the damage") {
  const auto log = temp("sim.lcm"), damaged = temp("damaged.lcm");
  tools::SimulationOptions so;
  so.duration_s = 20;
  {
    runtime::LogWriter w(log);
    tools::simulate(so, w);
    w.flush();
  }
  std::vector<uint8_t> b;
  {
    std::ifstream in(log, std::ios::binary);
    b.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  // The data length of the event in the middle of the file: 16 MiB.
  size_t pos = 0, events = 0;
  std::vector<size_t> starts;
  while (pos + 28 <= b.size()) {
    starts.push_back(pos);
    const auto be32 = [&](size_t at) {
      return (uint32_t{b[at]} << 24) | (uint32_t{b[at + 1]} << 16) | (uint32_t{b[at + 2]} << 8) | b[at + 3];
    };
    pos += 28 + be32(pos + 20) + be32(pos + 24);
    ++events;
  }
  const size_t mid = starts[events / 2];
  b[mid + 24] = 0x01, b[mid + 25] = 0x00, b[mid + 26] = 0x00, b[mid + 27] = 0x00;
  std::ofstream(damaged, std::ios::binary)
      .write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
  const config::DaemonConfig cfg;
  const auto clean = tools::replay_log(log, cfg);
  const auto r = tools::replay_log(damaged, cfg);
  CHECK(clean.records == static_cast<int64_t>(events));
  CHECK_FALSE(clean.log_damage.damaged());
  CHECK(r.records == static_cast<int64_t>(events) - 1);  // before: replay stopped at the damage, half the file
  CHECK(r.log_damage.bad_events == 1);
  CHECK(r.log_damage.skipped_bytes == static_cast<int64_t>(starts[events / 2 + 1] - mid));
  std::remove(log.c_str());
  std::remove(damaged.c_str());
}
