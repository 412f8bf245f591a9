// LCM log -> MCAP -> LCM log gives the same events (channel, timestamp, bytes, order), malformed, foreign and
// non-UTF-8 messages included; a damaged MCAP is refused naming the file.
#include "viewer/lcm_mcap.hpp"
#include "daemon/runtime/lcm_log.hpp"
#include "temp_path.hpp"

#include <doctest/doctest.h>
#include <sextant/fused_pose_t.hpp>
#include <sextant/odometry_t.hpp>

#include <cstdio>
#include <limits>

using namespace sextant;
using sextant::viewer::test::temp_path;

TEST_CASE("LCM -> MCAP -> LCM loses nothing") {
  const auto lcm = temp_path("in.lcm"), mcap = temp_path("in.mcap"), back = temp_path("back.lcm");
  {
    runtime::LogWriter w(lcm);
    for (int i = 0; i < 500; ++i) {
      sextant::fused_pose_t p{};
      p.utime = 1000000 + i * 10000;
      p.source = "robot" + std::to_string(i % 3);
      p.estimator = "ekf";
      p.position[0] = 0.1 * i;
      p.orientation[0] = 1;
      w.write(p.utime, "FUSED_POSE", p);
      if (i % 50 == 0) {
        sextant::odometry_t o{};
        o.utime = p.utime;
        o.source = "\xff\xfe not UTF-8";  // no JSON form: kept raw
        o.orientation[0] = 1;
        o.covariance[0] = std::numeric_limits<double>::quiet_NaN();
        w.write(o.utime - 3, "ODOMETRY", o);
        const uint8_t junk[] = {1, 2, 3, 4, 5};
        w.write_raw(-5, "NOT_SEXTANT", junk, sizeof junk);  // a negative timestamp, foreign bytes
      }
    }
    w.flush();
  }
  const auto r = viewer::convert_lcm_to_mcap(lcm, mcap, {4096, 3, "", ""});
  CHECK(r.events == 520);
  CHECK(r.raw == 20);
  CHECK(r.statistics.chunk_count > 1);
  const auto b = viewer::convert_mcap_to_lcm(mcap, back);
  CHECK(b.events == 520);
  CHECK(b.views_skipped == 2 * 500);  // a PoseInFrame and a /tf message per pose
  const auto a = runtime::LogReader::read_all(lcm), c = runtime::LogReader::read_all(back);
  REQUIRE(a.size() == c.size());
  for (size_t i = 0; i < a.size(); ++i) {
    CAPTURE(i);
    CHECK(a[i].channel == c[i].channel);
    CHECK(a[i].timestamp == c[i].timestamp);
    CHECK(a[i].data == c[i].data);
  }
  for (const auto& p : {lcm, mcap, back}) std::remove(p.c_str());
}

TEST_CASE("convert lcm refuses a file that is not MCAP, naming it") {
  const auto path = temp_path("not.mcap");
  {
    runtime::LogWriter w(path);
    w.write_raw(1, "X", "abc", 3);
  }
  CHECK_THROWS_WITH_AS(viewer::convert_mcap_to_lcm(path, temp_path("never.lcm")), doctest::Contains(path.c_str()),
                       std::runtime_error);
  std::remove(path.c_str());
}
