// The bearing simulator's false alarms (sim/simulator.hpp): with a clutter region they lie in each sensor's field
// of view over that box (checked against bounds computed here from the box's corners and horizontal distances,
// not with assoc::field_of_view), spread over it, and their number is Poisson with the configured mean; without a
// region most of them point away from it; a malformed region is an error.
#include "daemon/runtime/lcm_log.hpp"
#include "sim/simulator.hpp"

#include <sextant/bearing_scan_t.hpp>

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>

#include <unistd.h>

using namespace sextant;

namespace {

const Eigen::Vector3d kLo(-30, -20, 4), kHi(30, 20, 16);

struct Clutter {
  tools::SimulationSummary summary;
  int64_t detections = 0, in_view = 0, left_half = 0;
};

double wrap(double a) { return std::remainder(a, 2 * M_PI); }

// Every detection of a simulated run (P_D = 0: all false alarms) tested against the box's view from its sensor.
Clutter simulate_clutter(bool in_region) {
  const auto log =
      (std::filesystem::temp_directory_path() / ("sextant_clutter_" + std::to_string(::getpid()) + ".lcm")).string();
  tools::SimulationOptions o;
  o.duration_s = 30, o.seed = 7, o.p_detect = 0, o.clutter = 3;
  if (in_region) o.clutter_region_min = {kLo.x(), kLo.y(), kLo.z()}, o.clutter_region_max = {kHi.x(), kHi.y(), kHi.z()};
  Clutter c;
  {
    runtime::LogWriter w(log);
    c.summary = tools::simulate(o, w);
  }
  const double pad = 5 * o.bearing_sensor_sigma + 1e-9;
  for (const auto& r : runtime::LogReader::read_all(log)) {
    if (r.channel != "BEARINGS") continue;
    sextant::bearing_scan_t m;
    REQUIRE(runtime::decode_message(r.data, m));
    const Eigen::Vector3d s(m.sensor_position[0], m.sensor_position[1], m.sensor_position[2]);
    REQUIRE(s.z() < kLo.z());  // the elevation bounds below assume the box above the sensors
    // Azimuths: relative to the box centre's direction, the extremes over the box are at its corners (the sensors
    // are outside its horizontal extent).  Elevations: between the bottom seen from the farthest horizontal point
    // and the top seen from the nearest one.
    const double centre = std::atan2(0.5 * (kLo.y() + kHi.y()) - s.y(), 0.5 * (kLo.x() + kHi.x()) - s.x());
    double az_lo = 1e9, az_hi = -1e9, d_max = 0;
    for (double x : {kLo.x(), kHi.x()})
      for (double y : {kLo.y(), kHi.y()}) {
        const double a = wrap(std::atan2(y - s.y(), x - s.x()) - centre);
        az_lo = std::min(az_lo, a), az_hi = std::max(az_hi, a),
        d_max = std::max(d_max, std::hypot(x - s.x(), y - s.y()));
      }
    const double d_min = std::hypot(std::max({kLo.x() - s.x(), 0.0, s.x() - kHi.x()}),
                                    std::max({kLo.y() - s.y(), 0.0, s.y() - kHi.y()}));
    const double el_lo = std::atan2(kLo.z() - s.z(), d_max), el_hi = std::atan2(kHi.z() - s.z(), d_min);
    for (const auto& d : m.detections) {
      ++c.detections;
      const double a = wrap(d.azimuth - centre);
      c.in_view += a >= az_lo - pad && a <= az_hi + pad && d.elevation >= el_lo - pad && d.elevation <= el_hi + pad;
      c.left_half += a < 0.5 * (az_lo + az_hi);
    }
  }
  std::remove(log.c_str());
  return c;
}

}  // namespace

TEST_CASE("simulated false alarms in a clutter region lie in each sensor's field of view over it") {
  const auto c = simulate_clutter(true);
  const auto& s = c.summary;
  MESSAGE(c.detections << " false alarms in " << s.bearing_scans << " scans, " << c.in_view << " in view, "
                       << c.left_half << " left of the middle azimuth");
  CHECK(s.detections == 0);
  CHECK(c.detections == s.false_alarms);
  // Poisson(3) per sensor and scan: the total within 4 standard deviations of its mean.
  const double mean = 3.0 * static_cast<double>(s.bearing_scans);
  REQUIRE(s.bearing_scans >= 200);
  CHECK(std::abs(static_cast<double>(c.detections) - mean) < 4 * std::sqrt(mean));
  CHECK(c.in_view == c.detections);
  // Spread over the view (uniform in azimuth): about half on each side of the middle.
  const double half = static_cast<double>(c.left_half) / static_cast<double>(c.detections);
  CHECK(half > 0.4);
  CHECK(half < 0.6);
}

TEST_CASE("without a clutter region most simulated false alarms point away from the targets' region") {
  const auto c = simulate_clutter(false);
  MESSAGE(c.in_view << " of " << c.detections << " false alarms in the region's view");
  REQUIRE(c.detections > 500);
  CHECK(c.in_view < c.detections / 2);
}

TEST_CASE("a malformed clutter region is an error") {
  runtime::LogWriter w(
      (std::filesystem::temp_directory_path() / ("sextant_clutter_bad_" + std::to_string(::getpid()) + ".lcm"))
          .string());
  tools::SimulationOptions o;
  o.clutter_region_min = {0, 0, 0};
  CHECK_THROWS_AS(tools::simulate(o, w), std::invalid_argument);  // max missing
  o.clutter_region_max = {1, 1};
  CHECK_THROWS_AS(tools::simulate(o, w), std::invalid_argument);  // 2 numbers
  o.clutter_region_max = {1, 0, 1};
  CHECK_THROWS_AS(tools::simulate(o, w), std::invalid_argument);  // empty on y
  std::remove(w.path().c_str());
}
