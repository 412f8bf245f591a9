// One identity, one sender (source_claims.hpp): through the intake, as bytes from two senders that use one source.
#include "daemon/runtime/intake.hpp"
#include "daemon/runtime/source_claims.hpp"
#include "daemon/runtime/encode_message.hpp"

#include <doctest/doctest.h>

using namespace sextant;
using namespace sextant::runtime;

namespace {

std::vector<uint8_t> odometry(const std::string& sender, int64_t seq, int64_t utime, double x) {
  engine::Odometry o;
  o.utime = utime;
  o.source = "robot1";
  o.planar = true;
  o.pose.position = Eigen::Vector3d(x, 0, 0);
  o.covariance = Eigen::Matrix<double, 6, 6>::Identity() * 0.01;
  return encode(to_message(o, sender, seq));
}

}  // namespace

TEST_CASE(
    "source claims: a second sender of an active source is refused and counted, it takes over after the first goes "
    "silent") {
  ChannelStats stats;
  Intake intake(stats);
  intake.add_channel("ODOMETRY", InputKind::kOdometry);
  const int64_t t0 = 1'700'000'000'000'000;
  int accepted_a = 0, accepted_b = 0;
  // Two senders 100 m apart, alternating every 10 ms for one second.
  for (int k = 0; k < 100; ++k) {
    const bool a = k % 2 == 0;
    const auto bytes = odometry(a ? "driver_a" : "driver_b", k / 2, t0 + k * 10'000, a ? 1.5 + 0.001 * k : 101.5);
    if (intake.accept("ODOMETRY", bytes.data(), bytes.size(), Arrival::now())) (a ? accepted_a : accepted_b)++;
  }
  CHECK(accepted_a == 50);
  CHECK(accepted_b == 0);
  CHECK(intake.source_claimed() == 50);
  CHECK(stats.snapshot().at("ODOMETRY").reasons.at("source_claimed") == 50);
  // driver_a stops; after source_handover_s (2 s of data time) driver_b holds the source, and driver_a is refused.
  const int64_t later = t0 + 1'000'000 + 2'000'000;
  auto b = odometry("driver_b", 100, later, 1.6);
  CHECK(intake.accept("ODOMETRY", b.data(), b.size(), Arrival::now()));
  auto a = odometry("driver_a", 100, later + 10'000, 1.6);
  CHECK_FALSE(intake.accept("ODOMETRY", a.data(), a.size(), Arrival::now()));
}

TEST_CASE("source claims: the table is bounded, the claim silent longest gives its place") {
  SourceClaims claims(2.0, 2);
  CHECK(claims.claim("x", "s1", 10));
  CHECK(claims.claim("y", "s2", 20));
  CHECK(claims.claim("z", "s3", 30));  // x (silent longest) forgotten
  CHECK(claims.claim("x", "s4", 40));  // a new claim
  CHECK_FALSE(claims.claim("z", "s1", 50));
  CHECK(claims.refused() == 1);
}
