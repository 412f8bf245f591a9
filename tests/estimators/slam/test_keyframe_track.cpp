// The keyframe track's time resolution (exact, between and outside keyframe times, through thinned keyframes), its
// sighting anchors (interpolation on the group against the arc of a constant twist worked out by hand) and the
// odometry path covariance (a heading error turned into a lateral one by the lever arm, forwards and backwards).
#include "estimators/slam/keyframe_track.hpp"

#include "estimators/lie/se2.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>

using namespace sextant;
using namespace sextant::slam;

namespace {

SE3 planar_pose(double x, double y, double yaw) { return SE2(x, y, yaw).to_se3(); }

Matrix6d diagonal(double x, double y, double yaw) {
  Matrix6d c = Matrix6d::Zero();
  c(0, 0) = x, c(1, 1) = y, c(5, 5) = yaw;
  return c;
}

TrackKeyframe keyframe_at(const KeyframeTrack& track, int64_t utime, const SE3& odom, const Matrix6d& edge_covariance) {
  TrackKeyframe k;
  k.utime = utime;
  k.odom = odom;
  k.variable = static_cast<int>(track.keyframes().size());
  if (!track.empty()) k.edge = track.newest().odom.between(odom), k.edge_covariance = edge_covariance;
  return k;
}

/// Odometry along x, a message every 100 us at x = t / 200 metres, keyframes at 0, 200 and 400 us (x = 0, 1, 2).
KeyframeTrack straight_track() {
  KeyframeTrack track;
  for (int64_t t = 0; t <= 400; t += 100) {
    const SE3 pose = planar_pose(static_cast<double>(t) / 200.0, 0, 0);
    track.advance(t, pose, Matrix6d::Zero(), 100);
    if (t % 200 == 0)
      track.add_keyframe(keyframe_at(track, t, pose, diagonal(0.01 * static_cast<double>(t), 0.02, 0.03)));
  }
  return track;
}

}  // namespace

TEST_CASE(
    "keyframe track: a time resolves to its keyframe exactly, between keyframes through the odometry, not outside") {
  const KeyframeTrack track = straight_track();
  REQUIRE(track.keyframes().size() == 3);
  CHECK(track.keyframes()[1].id == 1);
  const int64_t tolerance = 150;

  // By id at its own time, and by time alone: the keyframe itself, no motion, no covariance.
  for (const int64_t id : {int64_t{1}, int64_t{-1}}) {
    const auto p = track.resolve(id, 200, tolerance);
    REQUIRE(p);
    CHECK(p->keyframe == 1);
    CHECK(p->motion.translation().norm() == 0.0);
    CHECK(p->covariance.isZero());
  }
  // An id whose keyframe is at another time is not taken: the time decides.  300 us is 100 us from both keyframe 1
  // and keyframe 2; the later one wins the tie, and the odometry from it to 300 us is 0.5 m backwards.
  const auto between = track.resolve(1, 300, tolerance);
  REQUIRE(between);
  CHECK(between->keyframe == 2);
  CHECK(between->motion.translation().x() == doctest::Approx(-0.5));
  CHECK(between->motion.translation().y() == doctest::Approx(0.0));
  CHECK(between->covariance.isZero());
  // 100 us is as far from keyframe 0 as from keyframe 1: the later one again, 0.5 m back.
  const auto early = track.resolve(-1, 100, tolerance);
  REQUIRE(early);
  CHECK(early->keyframe == 1);
  CHECK(early->motion.translation().x() == doctest::Approx(-0.5));
  // A time without an odometry message at it cannot be moved onto a keyframe.
  CHECK_FALSE(track.resolve(-1, 250, tolerance));
  // Past the tolerance after the newest keyframe, and before any odometry.
  CHECK_FALSE(track.resolve(-1, 600, tolerance));
  CHECK_FALSE(track.resolve(-1, -500, tolerance));
}

TEST_CASE(
    "keyframe track: a thinned keyframe's time lands on the keyframe before it with the composed edge's covariance") {
  KeyframeTrack track = straight_track();
  // Thin keyframe 1: keyframe 2's edge now spans 0 -> 2 with a covariance of its own.
  std::vector<TrackKeyframe> kept = {track.keyframes()[0], track.keyframes()[2]};
  kept[1].edge = planar_pose(2, 0, 0);
  kept[1].edge_covariance = diagonal(0.5, 0.6, 0.7);
  track.replace_keyframes(kept, {ThinnedKeyframe{1, 200, track.keyframes()[1].odom}});
  REQUIRE(track.keyframes().size() == 2);
  REQUIRE(track.thinned().size() == 1);
  const auto p = track.resolve(1, 200, 150);  // 200 us from both kept keyframes: beyond the tolerance
  REQUIRE(p);
  CHECK(p->keyframe == 0);
  CHECK(p->motion.translation().x() == doctest::Approx(1.0));
  CHECK(p->covariance == diagonal(0.5, 0.6, 0.7));
}

TEST_CASE("keyframe track: of each place's thinned records the newest visits stay, in time order") {
  // Two keyframes 1 s apart (x = 0 and 5 m), odometry only at their times.
  KeyframeTrack track;
  for (const int64_t t : {int64_t{0}, int64_t{1000000}}) {
    const SE3 pose = planar_pose(static_cast<double>(t) / 200000.0, 0, 0);
    track.advance(t, pose, Matrix6d::Zero(), 100);
    track.add_keyframe(keyframe_at(track, t, pose, diagonal(0.5, 0.6, 0.7)));
  }
  const std::vector<TrackKeyframe> kept = track.keyframes();
  const KeyframePlace a{0, 0, 0, 3}, b{1, 0, 0, 3};
  constexpr auto per_place = static_cast<int64_t>(KeyframeTrack::kThinnedRecordsPerPlace);
  const auto record = [](int64_t utime, const KeyframePlace& place) {
    return ThinnedKeyframe{utime, utime, planar_pose(static_cast<double>(utime) / 200.0, 0, 0), place};
  };
  // Thinnings of ten records each (times 1, 2, ... us, between the keyframes), out of time order within each; place a
  // visited five times as often as the whole bound, b once.
  int64_t next = 1;
  std::vector<ThinnedKeyframe> batch;
  track.replace_keyframes(kept, {record(next++, b)});
  while (next <= 5 * per_place) {
    batch.push_back(record(next++, a));
    if (batch.size() == 10) {
      std::reverse(batch.begin(), batch.end());
      track.replace_keyframes(kept, batch);
      batch.clear();
    }
  }
  track.replace_keyframes(kept, batch);
  const auto& records = track.thinned();
  CHECK(std::is_sorted(records.begin(), records.end(),
                       [](const ThinnedKeyframe& x, const ThinnedKeyframe& y) { return x.utime < y.utime; }));
  CHECK(records.front().utime == 1);  // b's only visit
  const auto of_a = static_cast<int64_t>(records.size()) - 1;
  CHECK(of_a >= per_place);
  CHECK(of_a <= per_place + per_place / 4 + per_place + 10);  // the bound, and what came since it was enforced
  CHECK(records.back().utime == next - 1);
  CHECK(records[1].utime == next - of_a);  // a's newest visits, none missing
  // A forgotten visit no longer resolves (no odometry pose recorded at its time); a kept one lands on keyframe 0.
  CHECK_FALSE(track.resolve(-1, 2, 0));
  const auto p = track.resolve(-1, records[1].utime, 0);
  REQUIRE(p);
  CHECK(p->keyframe == 0);
  CHECK(p->motion.translation().x() == doctest::Approx(static_cast<double>(records[1].utime) / 200.0));
  CHECK(p->covariance == diagonal(0.5, 0.6, 0.7));
}

TEST_CASE("keyframe track: a sighting between two odometry messages is anchored on the arc between them") {
  // A constant twist: v = 2 m/s forward, w = 0.8 rad/s, odometry at 0 and 1 s (keyframe at 0).  On SE(2) the motion
  // is the arc x = v/w sin(w s), y = v/w (1 - cos(w s)), heading w s; interpolation on the group at a follows it.
  const double v = 2.0, w = 0.8;
  const auto arc = [&](double s) { return planar_pose(v / w * std::sin(w * s), v / w * (1 - std::cos(w * s)), w * s); };
  KeyframeTrack track;
  track.advance(0, arc(0), Matrix6d::Zero(), 100);
  track.add_keyframe(keyframe_at(track, 0, arc(0), Matrix6d::Zero()));
  const Matrix6d q = diagonal(0.01, 0.02, 0.003);
  track.extend_since_keyframe(arc(0).between(arc(1)), q);
  track.advance(1000000, arc(1), Matrix6d::Zero(), 100);

  const auto a = track.anchor_at(250000);
  REQUIRE(a);
  CHECK(a->keyframe == 0);
  const SE3 expected = arc(0.25);
  CHECK(a->motion.translation().x() == doctest::Approx(expected.translation().x()).epsilon(1e-12));
  CHECK(a->motion.translation().y() == doctest::Approx(expected.translation().y()).epsilon(1e-12));
  CHECK(SE2::from_se3(a->motion).angle() == doctest::Approx(0.2).epsilon(1e-12));
  // No keyframe after it: D's covariance is the odometry's since the keyframe (here one increment's, from zero).
  CHECK((a->covariance - q).norm() < 1e-15);
  // At the latest message exactly: the latest pose.
  const auto last = track.anchor_at(1000000);
  REQUIRE(last);
  CHECK(last->motion.translation().x() == doctest::Approx(arc(1).translation().x()));
  // Before the first keyframe: none.
  CHECK_FALSE(track.anchor_at(-1));
  CHECK_FALSE(track.keyframe_at_or_before(-1));
}

TEST_CASE("keyframe track: the odometry path's covariance turns a heading error into a lateral one, and back") {
  // Keyframe 1 is reached by a pure turn of 0 rad with heading variance s2; keyframe 2 lies d metres ahead with no
  // uncertainty of its own.  A heading error delta at keyframe 1 puts keyframe 2 at (d, d delta) with heading delta,
  // i.e. a right perturbation (0, d delta, delta): var y = d^2 s2, cov(y, yaw) = d s2, var yaw = s2.
  const double s2 = 0.01, d = 3.0;
  KeyframeTrack track;
  track.advance(1, planar_pose(0, 0, 0), Matrix6d::Zero(), 100);
  track.add_keyframe(keyframe_at(track, 1, planar_pose(0, 0, 0), Matrix6d::Zero()));
  track.advance(2, planar_pose(0, 0, 0), Matrix6d::Zero(), 100);
  track.add_keyframe(keyframe_at(track, 2, planar_pose(0, 0, 0), diagonal(0, 0, s2)));
  track.advance(3, planar_pose(d, 0, 0), Matrix6d::Zero(), 100);
  track.add_keyframe(keyframe_at(track, 3, planar_pose(d, 0, 0), Matrix6d::Zero()));

  const auto [forward, P] = track.odometry_path(0, 2);
  CHECK(forward.translation().x() == doctest::Approx(d));
  CHECK(P(1, 1) == doctest::Approx(d * d * s2));
  CHECK(P(1, 5) == doctest::Approx(d * s2));
  CHECK(P(5, 5) == doctest::Approx(s2));
  CHECK(std::abs(P(0, 0)) < 1e-15);
  // Backwards, keyframe 0 seen from keyframe 2 is (-d cos delta - ..., ...) = (-d, 0) to first order: the lever arm
  // cancels, only the heading variance is left.
  const auto [backward, Q] = track.odometry_path(2, 0);
  CHECK(backward.translation().x() == doctest::Approx(-d));
  CHECK(std::abs(Q(1, 1)) < 1e-12);
  CHECK(std::abs(Q(1, 5)) < 1e-12);
  CHECK(Q(5, 5) == doctest::Approx(s2));
}

TEST_CASE("keyframe track: the odometry history is bounded (the older half goes) and its times stop resolving") {
  KeyframeTrack track;
  for (int64_t t = 0; t < 10; ++t) track.advance(t, planar_pose(static_cast<double>(t), 0, 0), Matrix6d::Zero(), 4);
  CHECK(track.odometry().size() <= 4);
  CHECK(track.odometry().back().first == 9);
  track.add_keyframe(keyframe_at(track, 9, planar_pose(9, 0, 0), Matrix6d::Zero()));
  CHECK(track.resolve(-1, 8, 5));         // still recorded
  CHECK_FALSE(track.resolve(-1, 2, 10));  // forgotten
}
