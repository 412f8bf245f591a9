// The keyframe rule of the Kinect visual-odometry paper (Sensors and Microsystems 2019): thresholds k1/k2 at
// their edges, the weights, rejection keeping the reference, the planar mode, bad poses and bad options.
#include "estimators/keyframe/keyframe_selector.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

using namespace sextant;

namespace {

SE3 translation(double x, double y = 0, double z = 0) { return SE3(SO3(), Eigen::Vector3d(x, y, z)); }

Vector6d xi(double rx, double ry, double rz, double wx, double wy, double wz) {
  Vector6d v;
  v << rx, ry, rz, wx, wy, wz;
  return v;
}

}  // namespace

TEST_CASE("keyframe selector: the first pose is a keyframe, whatever it is") {
  KeyframeSelector s;
  CHECK(s.decide(SE3::exp(xi(100, -50, 3, 0.3, -0.2, 2.0))) == KeyframeDecision::kKeyframe);
  CHECK(s.accepted() == 1);
  CHECK(s.last_magnitude() == 0);
}

TEST_CASE("keyframe selector: k1 and k2 are inclusive edges of the keyframe band") {
  KeyframeSelectorOptions o;
  o.k1 = 0.3;
  o.k2 = 5.0;
  const double e = 1e-9;
  struct Case {
    double x;
    KeyframeDecision expected;
  };
  for (const Case c : {Case{0.3 - e, KeyframeDecision::kTooClose}, Case{0.3 + e, KeyframeDecision::kKeyframe},
                       Case{5.0 - e, KeyframeDecision::kKeyframe}, Case{5.0 + e, KeyframeDecision::kImplausible},
                       Case{0.0, KeyframeDecision::kTooClose}}) {
    CAPTURE(c.x);
    KeyframeSelector s(o);
    s.decide(translation(1, 2, 3));
    CHECK(s.decide(translation(1 + c.x, 2, 3)) == c.expected);
    CHECK(s.last_magnitude() == doctest::Approx(c.x).epsilon(1e-12));
  }
  // Exactly on k2 (a pure translation's logarithm is the translation itself).
  KeyframeSelector s(o);
  s.decide(SE3());
  CHECK(s.decide(translation(0, 0, 5.0)) == KeyframeDecision::kKeyframe);
}

TEST_CASE("keyframe selector: L = sqrt(w_t |rho|^2 + w_r |phi|^2) of the logarithm of the relative motion") {
  const SE3 kf = SE3::exp(xi(3, 1, -2, 0.1, 0.2, 1.2));
  const Vector6d mu = xi(0.12, -0.09, 0.05, 0.1, -0.05, 0.15);  // |rho|^2 = 0.025, |phi|^2 = 0.035
  const SE3 pose = kf * SE3::exp(mu);
  for (const auto& weights : {std::pair{1.0, 1.0}, std::pair{4.0, 0.0}, std::pair{0.0, 9.0}, std::pair{2.5, 0.5}}) {
    const double wt = weights.first, wr = weights.second;  // plain variables: CAPTURE's lambda takes them (clang 14)
    KeyframeSelectorOptions o;
    o.translation_weight = wt;
    o.rotation_weight = wr;
    o.k1 = 0.3;
    KeyframeSelector s(o);
    s.decide(kf);
    const double expected = std::sqrt(wt * 0.025 + wr * 0.035);
    const auto d = s.decide(pose);
    CAPTURE(wt);
    CAPTURE(wr);
    CHECK(s.last_magnitude() == doctest::Approx(expected).epsilon(1e-9));
    CHECK(d == (expected >= 0.3 ? KeyframeDecision::kKeyframe : KeyframeDecision::kTooClose));
  }
  // The cases above straddle k1: 0.2449 (1,1) too close, 0.3162 (4,0) keyframe, 0.5612 (0,9) keyframe.
}

TEST_CASE("keyframe selector: a rotation in place becomes a keyframe through the rotation weight") {
  KeyframeSelectorOptions o;
  o.k1 = 0.5;
  o.rotation_weight = 1.0;
  KeyframeSelector unit(o);
  o.rotation_weight = 4.0;
  KeyframeSelector heavy(o);
  const SE3 turned(SO3::exp(Eigen::Vector3d(0, 0, 0.3)), Eigen::Vector3d::Zero());
  unit.decide(SE3());
  heavy.decide(SE3());
  CHECK(unit.decide(turned) == KeyframeDecision::kTooClose);   // L = 0.3
  CHECK(heavy.decide(turned) == KeyframeDecision::kKeyframe);  // L = 0.6
}

TEST_CASE("keyframe selector: the motion is measured from the last keyframe, not from the last pose") {
  KeyframeSelector s;  // k1 = 0.3
  s.decide(SE3());
  CHECK(s.decide(translation(0.1)) == KeyframeDecision::kTooClose);
  CHECK(s.decide(translation(0.2)) == KeyframeDecision::kTooClose);
  CHECK(s.decide(translation(0.35)) == KeyframeDecision::kKeyframe);
  CHECK(s.decide(translation(0.5)) == KeyframeDecision::kTooClose);  // 0.15 from the keyframe at 0.35
  CHECK(s.too_close() == 3);
  CHECK(s.accepted() == 2);
  CHECK(s.reference()->translation().x() == 0.35);
}

TEST_CASE("keyframe selector: an implausible jump is rejected, counted, and keeps the reference") {
  KeyframeSelector s;  // k1 = 0.3, k2 = 5
  s.decide(SE3());
  CHECK(s.decide(translation(20)) == KeyframeDecision::kImplausible);
  CHECK(s.last_magnitude() == doctest::Approx(20));
  CHECK(s.rejected() == 1);
  CHECK(s.reference()->translation().norm() == 0);
  // Measured from the kept reference (0 m), not from the rejected 20 m.
  CHECK(s.decide(translation(0.5)) == KeyframeDecision::kKeyframe);
  CHECK(s.last_magnitude() == doctest::Approx(0.5));
  CHECK(s.accepted() == 2);
  CHECK(s.rejected() == 1);
}

TEST_CASE("keyframe selector: spikes are rejected, a persistent jump re-anchors after reanchor_after poses") {
  KeyframeSelectorOptions o;  // k1 = 0.3, k2 = 5
  o.reanchor_after = 4;
  KeyframeSelector s(o);
  s.decide(SE3());
  // A spike of three poses (one short of re-anchoring), then back: all rejected, the reference stays at 0.
  for (double x : {20.0, 20.1, 20.2}) CHECK(s.decide(translation(x)) == KeyframeDecision::kImplausible);
  CHECK(s.jump_run() == 3);
  CHECK(s.decide(translation(0.1)) == KeyframeDecision::kTooClose);
  CHECK(s.jump_run() == 0);
  CHECK(s.reference()->translation().norm() == 0);
  // Wild poses that disagree with each other (each > k2 from the one before) never re-anchor.
  for (int k = 0; k < 20; ++k) CHECK(s.decide(translation(k % 2 ? 30.0 : -30.0)) == KeyframeDecision::kImplausible);
  CHECK(s.jump_run() == 1);
  CHECK(s.reanchored() == 0);
  CHECK(s.rejected() == 23);
  // A real jump to 40 m, the body moving on from there: rejected three times, the fourth pose is the new reference.
  CHECK(s.decide(translation(0.2)) == KeyframeDecision::kTooClose);  // ends the wild run
  for (double x : {40.0, 40.2, 40.4}) CHECK(s.decide(translation(x)) == KeyframeDecision::kImplausible);
  CHECK(s.decide(translation(40.6)) == KeyframeDecision::kReanchored);
  CHECK(s.reanchored() == 1);
  CHECK(s.rejected() == 26);
  CHECK(s.jump_run() == 0);
  CHECK(s.reference()->translation().x() == 40.6);
  // Keyframing resumes from there.
  CHECK(s.decide(translation(40.7)) == KeyframeDecision::kTooClose);
  CHECK(s.decide(translation(41.0)) == KeyframeDecision::kKeyframe);
  // A non-finite pose ends a run; reanchor_after = 0 never re-anchors.
  for (double x : {0.0, 0.1, 0.2}) CHECK(s.decide(translation(x)) == KeyframeDecision::kImplausible);
  CHECK(s.decide(translation(std::numeric_limits<double>::quiet_NaN())) == KeyframeDecision::kImplausible);
  CHECK(s.decide(translation(0.3)) == KeyframeDecision::kImplausible);
  CHECK(s.jump_run() == 1);
  o.reanchor_after = 0;
  KeyframeSelector never(o);
  never.decide(SE3());
  for (int k = 0; k < 100; ++k) CHECK(never.decide(translation(50 + 0.1 * k)) == KeyframeDecision::kImplausible);
  CHECK(never.reanchored() == 0);
}

namespace {
// True when the selector's reference is `pose` to the bit (both none, or the same numbers).
bool refers_to(const KeyframeSelector& s, const std::optional<SE3>& pose) {
  const auto& r = s.reference();
  if (!r || !pose) return !r && !pose;
  return r->translation() == pose->translation() &&
         r->rotation().quaternion().coeffs() == pose->rotation().quaternion().coeffs();
}
}  // namespace

TEST_CASE("keyframe selector: reset_reference goes back to a keyframe the caller used and ends a jump run") {
  KeyframeSelectorOptions o;
  o.k1 = 0.3;
  o.k2 = 5.0;
  o.reanchor_after = 3;
  KeyframeSelector s(o);
  CHECK(s.decide(translation(0)) == KeyframeDecision::kKeyframe);
  CHECK(s.decide(translation(4.9)) == KeyframeDecision::kKeyframe);  // the caller cannot use it: back to 0
  CHECK(refers_to(s, translation(4.9)));
  s.reset_reference(translation(0));
  CHECK(refers_to(s, translation(0)));
  CHECK_FALSE(refers_to(s, translation(4.9)));
  CHECK_FALSE(refers_to(s, std::nullopt));
  // Measured from 0 again: 5.3 is a jump (0.4 past the dropped keyframe would have been a keyframe), 0.2 too close.
  CHECK(s.decide(translation(5.3)) == KeyframeDecision::kImplausible);
  CHECK(s.last_magnitude() == doctest::Approx(5.3));
  CHECK(s.decide(translation(0.2)) == KeyframeDecision::kTooClose);
  // A run towards re-anchoring ends: two implausible poses, a reset, then it takes reanchor_after new ones.
  CHECK(s.decide(translation(10)) == KeyframeDecision::kImplausible);
  CHECK(s.decide(translation(10.1)) == KeyframeDecision::kImplausible);
  CHECK(s.jump_run() == 2);
  s.reset_reference(translation(0));
  CHECK(s.jump_run() == 0);
  CHECK(s.decide(translation(10.2)) == KeyframeDecision::kImplausible);
  CHECK(s.decide(translation(10.3)) == KeyframeDecision::kImplausible);
  CHECK(s.decide(translation(10.4)) == KeyframeDecision::kReanchored);
  // No reference: the next pose is the first keyframe.  Counters are not rewound.
  const int64_t accepted = s.accepted();
  s.reset_reference(std::nullopt);
  CHECK(refers_to(s, std::nullopt));
  CHECK(s.decide(translation(77)) == KeyframeDecision::kKeyframe);
  CHECK(s.accepted() == accepted + 1);
  CHECK_THROWS_AS(s.reset_reference(translation(std::nan(""))), std::invalid_argument);
  CHECK(refers_to(s, translation(77)));
}

TEST_CASE("keyframe selector: a non-finite pose is implausible and never becomes the reference") {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  KeyframeSelector s;
  CHECK(s.decide(translation(nan)) == KeyframeDecision::kImplausible);  // even as the first pose
  CHECK(!s.reference());
  CHECK(std::isnan(s.last_magnitude()));
  CHECK(s.decide(translation(1)) == KeyframeDecision::kKeyframe);
  CHECK(s.decide(translation(std::numeric_limits<double>::infinity())) == KeyframeDecision::kImplausible);
  CHECK(s.rejected() == 2);
  CHECK(s.reference()->translation().x() == 1);
}

TEST_CASE("keyframe selector: planar mode measures x, y, yaw only") {
  KeyframeSelectorOptions o;
  o.planar = true;
  KeyframeSelector planar(o);
  KeyframeSelector spatial;
  // 3 m up with a 0.5 rad roll and 0.1 m ahead: nothing in the plane.
  const SE3 bump(SO3::exp(Eigen::Vector3d(0.5, 0, 0)), Eigen::Vector3d(0.1, 0, 3));
  planar.decide(SE3());
  spatial.decide(SE3());
  CHECK(planar.decide(bump) == KeyframeDecision::kTooClose);
  CHECK(planar.last_magnitude() == doctest::Approx(0.1));
  CHECK(spatial.decide(bump) == KeyframeDecision::kKeyframe);
  // In the plane: SE(2) log of (x, y, yaw).
  const Eigen::Vector3d tau(0.2, 0.3, 0.4);
  const SE3 move = SE2::exp(tau).to_se3();
  CHECK(planar.magnitude(SE3(), move) == doctest::Approx(tau.norm()).epsilon(1e-12));
}

TEST_CASE("keyframe selector: options are validated") {
  const auto bad = [](KeyframeSelectorOptions o) { CHECK_THROWS_AS(KeyframeSelector{o}, std::invalid_argument); };
  KeyframeSelectorOptions o;
  o.k1 = -0.1;
  bad(o);
  o = {};
  o.k1 = 2, o.k2 = 2;
  bad(o);
  o = {};
  o.k2 = std::numeric_limits<double>::quiet_NaN();
  bad(o);
  o = {};
  o.k2 = std::numeric_limits<double>::infinity();
  bad(o);
  o = {};
  o.translation_weight = -1;
  bad(o);
  o = {};
  o.rotation_weight = std::numeric_limits<double>::quiet_NaN();
  bad(o);
  o = {};
  o.translation_weight = 0, o.rotation_weight = 0;
  bad(o);
  o = {};
  o.reanchor_after = -1;
  bad(o);
  o = {};
  o.k1 = 0;  // every motion except none is a keyframe: allowed
  CHECK_NOTHROW(KeyframeSelector{o});
  try {
    KeyframeSelectorOptions x;
    x.k1 = 3;
    x.k2 = 1;
    KeyframeSelector{x};
  } catch (const std::invalid_argument& e) {
    CHECK(std::string(e.what()).find("k1 = 3") != std::string::npos);
  }
}
