// The SLAM layer called from plain C++: keyframes from odometry, loops accepted, rejected, unmatched and waiting for
// the odometry, landmarks placed where their sightings put them (by hand) and a wrong sighting gated out, a body
// forgotten, and the state saved, restored and continued bit for bit.
#include "estimators/slam/slam_graph.hpp"
#include "estimators/slam/fleet_scenario.hpp"

#include "estimators/lie/se2.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <memory>

using namespace sextant;
using namespace sextant::slam;

namespace {

struct Recorder final : SlamListener {
  int updates = 0;
  std::vector<std::pair<int64_t, int64_t>> proposals;  // (new keyframe id, earlier keyframe id)
  void updated(const std::string&, int64_t, const graph::IncrementalStatus& status) override {
    CHECK(status.ok);
    ++updates;
  }
  void loop_proposed(const std::string&, int64_t, const KeyframeEstimate& a, const KeyframeEstimate& b, bool) override {
    proposals.emplace_back(a.id, b.id);
  }
};

SE3 planar_pose(double x, double y, double yaw) { return SE2(x, y, yaw).to_se3(); }

/// Message i of a body driving along x at 0.5 m per message, every 0.1 s, with a stated increment covariance.
OdometryInput odometry(int i) {
  OdometryInput o;
  o.utime = 100000 * int64_t{i};
  o.planar = true;
  o.pose = planar_pose(0.5 * i, 0, 0);
  Matrix6d q = Matrix6d::Zero();
  q(0, 0) = q(1, 1) = 1e-4, q(5, 5) = 1e-5;
  o.increment_covariance = q;
  o.covariance = q * (i + 1);
  return o;
}

LoopInput loop(int from, int to, double dx, double dy) {
  LoopInput l;
  l.utime_from = 100000 * int64_t{from}, l.utime_to = 100000 * int64_t{to};
  l.relative = planar_pose(0.5 * (to - from) + dx, dy, 0);
  l.information = Matrix6d::Identity() * 100;
  return l;
}

SightingsInput sighting_of(int i, int64_t id, double landmark_x, double landmark_y) {
  const double x = 0.5 * i;
  SightingsInput s;
  s.utime = 100000 * int64_t{i};
  s.planar = true;
  LandmarkSighting o;
  o.id = id;
  o.range = std::hypot(landmark_x - x, landmark_y);
  o.azimuth = std::atan2(landmark_y, landmark_x - x);
  o.covariance = Eigen::Vector3d(1e-4, 1e-5, 1).asDiagonal();
  s.sightings.push_back(o);
  return s;
}

}  // namespace

TEST_CASE("slam graph: keyframes from odometry, loops gated, unmatched and waiting, landmarks placed and gated") {
  SlamOptions options;
  SlamGraph slam(options);
  Recorder out;
  for (int i = 0; i < 10; ++i) slam.add_odometry("robot", odometry(i), out);
  CHECK(slam.counters().keyframes == 10);  // 0.5 m per message, k1 = 0.3 m: every message is a keyframe
  CHECK(out.updates == 10);
  REQUIRE(slam.keyframes("robot").size() == 10);
  CHECK(slam.keyframes("robot")[9].pose.translation().x() == doctest::Approx(4.5));
  CHECK(slam.keyframes("robot")[0].id == 0);
  for (const auto& [a, b] : out.proposals) CHECK(b < a);
  CHECK_FALSE(out.proposals.empty());
  slam.add_odometry("robot", odometry(9), out);  // not newer
  CHECK(slam.counters().odometry_out_of_order == 1);

  // A loop that agrees with the odometry is accepted; 3 m off it is far outside the gate.
  slam.add_loop("robot", loop(0, 9, 0.0, 0.02), out);
  CHECK(slam.counters().loops_accepted == 1);
  slam.add_loop("robot", loop(0, 9, 0.0, 3.0), out);
  CHECK(slam.counters().loops_rejected == 1);
  // A time without an odometry message is not moved onto a keyframe; a body without odometry is unknown.
  LoopInput between = loop(2, 7, 0, 0);
  between.utime_from += 30000;
  slam.add_loop("robot", between, out);
  CHECK(slam.counters().loops_unmatched == 1);
  slam.add_loop("nobody", loop(0, 1, 0, 0), out);
  CHECK(slam.counters().loops_unknown_source == 1);
  // A loop about a time the odometry has not reached waits for it, then is gated and accepted.
  slam.add_loop("robot", loop(3, 11, 0, 0), out);
  CHECK(slam.counters().loops_accepted == 1);
  slam.add_odometry("robot", odometry(10), out);
  CHECK(slam.counters().loops_accepted == 1);
  slam.add_odometry("robot", odometry(11), out);
  CHECK(slam.counters().loops_accepted == 2);

  // A landmark's first sighting puts it where the sighting says (keyframe 2 at x = 1; landmark at (1.5, 2)); a second
  // sighting from keyframe 6 agrees; one 1 m off is gated out.
  slam.add_sightings("robot", sighting_of(2, 5, 1.5, 2.0), out);
  REQUIRE(slam.landmarks("robot").size() == 1);
  CHECK(slam.landmarks("robot")[0].position.x() == doctest::Approx(1.5).epsilon(1e-3));
  CHECK(slam.landmarks("robot")[0].position.y() == doctest::Approx(2.0).epsilon(1e-3));
  slam.add_sightings("robot", sighting_of(6, 5, 1.5, 2.0), out);
  slam.add_sightings("robot", sighting_of(8, 5, 2.5, 2.0), out);
  CHECK(slam.counters().sightings_accepted == 2);
  CHECK(slam.counters().sightings_rejected == 1);
  CHECK(slam.counters().landmarks == 1);
  CHECK(slam.landmarks("robot")[0].sightings == 2);
  // Ahead of the odometry: waits, then anchored on the arc between two messages.
  slam.add_sightings("robot", sighting_of(12, 6, 6.0, -1.0), out);
  CHECK(slam.landmarks("robot").size() == 1);
  slam.add_odometry("robot", odometry(12), out);
  CHECK(slam.landmarks("robot").size() == 2);
  CHECK(slam.graph_keyframes() == 13);
  CHECK(slam.graph_landmarks() == 2);

  // A second body, then forgotten: the first body's graph keeps its keyframes; the smoother rebuilt without the other
  // body solves again, which moves the estimates by no more than the incremental solution's own convergence.
  const auto before = slam.keyframes("robot");
  for (int i = 0; i < 3; ++i) slam.add_odometry("other", odometry(i), out);
  CHECK(slam.graph_keyframes() == 16);
  slam.forget("other");
  CHECK(slam.graph_keyframes() == 13);
  CHECK(slam.bodies() == std::vector<std::string>{"robot"});
  const auto after = slam.keyframes("robot");
  REQUIRE(after.size() == before.size());
  for (size_t k = 0; k < after.size(); ++k)
    CHECK((after[k].pose.translation() - before[k].pose.translation()).norm() < 1e-3);
}

TEST_CASE("slam graph: loops waiting for the odometry are bounded per body and counted, waiting and dropped") {
  SlamOptions options;
  options.max_waiting_loops = 3;
  SlamGraph slam(options);
  Recorder out;
  for (int i = 0; i < 4; ++i) slam.add_odometry("robot", odometry(i), out);
  for (int i = 0; i < 2; ++i) slam.add_odometry("other", odometry(i), out);
  // Five loops ahead of the robot's odometry: three wait, two are dropped at the cap (not unmatched).
  for (int k = 0; k < 5; ++k) slam.add_loop("robot", loop(1, 6 + k, 0, 0), out);
  CHECK(slam.counters().loops_waiting == 3);
  CHECK(slam.counters().loops_waiting_dropped == 2);
  CHECK(slam.counters().loops_unmatched == 0);
  // Another body has its own bound.
  slam.add_loop("other", loop(0, 5, 0, 0), out);
  CHECK(slam.counters().loops_waiting == 4);
  CHECK(slam.counters().loops_waiting_dropped == 2);
  // The odometry reaches two of the robot's loops: they leave the waiting set (and are gated).
  for (int i = 4; i <= 7; ++i) slam.add_odometry("robot", odometry(i), out);
  CHECK(slam.counters().loops_waiting == 2);
  CHECK(slam.counters().loops_accepted == 2);
  // A saved state restores the waiting count; forgetting a body takes its waiting loops out.
  archive::ArchiveWriter w;
  slam.save(w);
  SlamGraph restored(options);
  archive::ArchiveReader r(w.data().data(), w.data().size(), "test");
  restored.load(r);
  CHECK(restored.counters().loops_waiting == 2);
  restored.forget("robot");
  CHECK(restored.counters().loops_waiting == 1);
  // 0: no loop waits.
  options.max_waiting_loops = 0;
  SlamGraph none(options);
  for (int i = 0; i < 2; ++i) none.add_odometry("robot", odometry(i), out);
  none.add_loop("robot", loop(0, 5, 0, 0), out);
  CHECK(none.counters().loops_waiting == 0);
  CHECK(none.counters().loops_waiting_dropped == 1);
}

TEST_CASE("slam graph: a state saved and restored continues bit for bit, and saves the same bytes") {
  SlamOptions options;
  SlamGraph a(options);
  Recorder out;
  for (int i = 0; i < 8; ++i) a.add_odometry("robot", odometry(i), out);
  a.add_sightings("robot", sighting_of(3, 1, 2.0, 1.0), out);
  a.add_loop("robot", loop(1, 7, 0.01, 0.0), out);
  a.add_loop("robot", loop(2, 9, 0.0, 0.0), out);               // waits for the odometry
  a.add_sightings("robot", sighting_of(9, 2, 3.0, -1.0), out);  // waits too

  archive::ArchiveWriter w;
  a.save(w);
  SlamGraph b(options);
  archive::ArchiveReader r(w.data().data(), w.data().size(), "test");
  b.load(r);
  CHECK_THROWS_AS(b.load(r), std::logic_error);
  // Saving refactorizes the saved layer, loading the restored one, from the same graph: the next saves agree byte for
  // byte but for the rebuilds counter (the saving layer counts its refactorization, the restored one does not; the
  // fifth int64 after the next variable id and the two thinning counts).
  archive::ArchiveWriter a_again, b_again;
  a.save(a_again);
  b.save(b_again);
  REQUIRE(b_again.data().size() == a_again.data().size());
  const size_t rebuilds_at = 8 * 5;
  CHECK(b_again.data().substr(0, rebuilds_at) == a_again.data().substr(0, rebuilds_at));
  CHECK(b_again.data().substr(rebuilds_at + 8) == a_again.data().substr(rebuilds_at + 8));
  CHECK(a.counters().rebuilds == b.counters().rebuilds + 1);

  for (int i = 8; i < 12; ++i) {
    a.add_odometry("robot", odometry(i), out);
    b.add_odometry("robot", odometry(i), out);
  }
  CHECK(a.counters().loops_accepted == 2);
  CHECK(b.counters().loops_accepted == 2);
  CHECK(b.landmarks("robot").size() == 2);
  const auto ka = a.keyframes("robot"), kb = b.keyframes("robot");
  REQUIRE(ka.size() == kb.size());
  for (size_t k = 0; k < ka.size(); ++k) {
    CHECK(ka[k].pose.translation() == kb[k].pose.translation());
    CHECK(ka[k].pose.rotation().quaternion().coeffs() == kb[k].pose.rotation().quaternion().coeffs());
  }
  // Damaged bytes are refused with the archive's error, not a crash.
  std::string cut = w.data().substr(0, w.data().size() / 2);
  SlamGraph c(options);
  archive::ArchiveReader damaged(cut.data(), cut.size(), "cut");
  CHECK_THROWS_AS(c.load(damaged), archive::ArchiveError);
}

TEST_CASE("slam graph: the solve period holds updates back in data time and solves them past it and at flush") {
  // Odometry every 0.1 s, every message a keyframe; a period of 0.35 s solves at 0, 0.4 and 0.8 s.
  SlamOptions held;
  held.solve_period_s = 0.35;
  SlamOptions every;
  every.solve_period_s = 0;
  SlamGraph a(held), b(every);
  Recorder out_a, out_b;
  for (int i = 0; i < 10; ++i) {
    a.add_odometry("robot", odometry(i), out_a);
    b.add_odometry("robot", odometry(i), out_b);
  }
  CHECK(out_b.updates == 10);
  CHECK(out_a.updates == 3);
  CHECK(a.counters().updates == 3);
  CHECK(a.counters().keyframes == 10);
  // Still owed (0.9 s, 0.1 s after the last solve): a loop that moves the last keyframes by centimetres waits too.
  LoopInput l = loop(2, 9, 0.0, 0.03);
  l.information = Matrix6d::Identity() * 1e4;
  a.add_loop("robot", l, out_a);
  b.add_loop("robot", l, out_b);
  CHECK(out_a.updates == 3);
  CHECK(a.counters().loops_accepted == 1);
  const double moved_b = b.keyframes("robot")[9].pose.translation().y();
  CHECK(std::abs(moved_b) > 0.01);                                         // the loop moved b's last keyframe
  CHECK(std::abs(a.keyframes("robot")[9].pose.translation().y()) < 1e-9);  // not yet a's

  // A saved and restored layer owes nothing (the save refactorizes) and keeps the clock: both continue alike.
  archive::ArchiveWriter w;
  a.save(w);
  SlamGraph c(held);
  archive::ArchiveReader r(w.data().data(), w.data().size(), "test");
  c.load(r);
  Recorder out_c;
  for (SlamGraph* g : {&a, &c}) {
    Recorder& o = g == &a ? out_a : out_c;
    g->add_odometry("robot", odometry(10), o);  // 1.0 s: within the period of the save's 0.9 s, held back
    g->add_sightings("robot", sighting_of(10, 7, 6.0, 1.0), o);
    g->flush(o);
    g->flush(o);  // nothing owed: nothing more
  }
  CHECK(out_c.updates == 1);
  b.add_odometry("robot", odometry(10), out_b);
  b.add_sightings("robot", sighting_of(10, 7, 6.0, 1.0), out_b);
  // Solved at the flush: the same answer as one update after every input (the same factors at their optimum).
  const auto ka = a.keyframes("robot"), kb = b.keyframes("robot"), kc = c.keyframes("robot");
  REQUIRE(ka.size() == kb.size());
  REQUIRE(kc.size() == kb.size());
  for (size_t k = 0; k < ka.size(); ++k) {
    CHECK((ka[k].pose.translation() - kb[k].pose.translation()).norm() < 1e-4);
    CHECK(ka[k].pose.translation() == kc[k].pose.translation());
  }
  REQUIRE(a.landmarks("robot").size() == 1);
  CHECK((a.landmarks("robot")[0].position - b.landmarks("robot")[0].position).norm() < 1e-4);
}

namespace {

// A robot on a 5 m circle, 0.4 m per keyframe (test::Robot, 0.8 rad/s, a message every 0.1 s), among 8 landmarks on
// an 8 m circle, seen within 7 m: its odometry turns 5 % too much, so where the map's landmarks lie relative to the
// first keyframe depends on how much of the data is kept.
struct CircleRun {
  const test::Robot robot{"robot", {0, 0}, 5, 0, 0.8};
  SE3 odom;  // the biased odometry's integrated pose
  static double at(int i) { return 0.1 * i; }
  OdometryInput odometry(int i) {
    if (i > 0) {
      const SE2 inc = robot.truth(at(i - 1)).inverse() * robot.truth(at(i));
      odom = odom * SE2(inc.translation().x(), inc.translation().y(), 1.05 * inc.angle()).to_se3();
    }
    OdometryInput o = test::odometry_at(robot, at(i));
    o.pose = odom;
    Matrix6d q = Matrix6d::Zero();
    q(0, 0) = q(1, 1) = 1e-4, q(5, 5) = 4e-4;
    o.increment_covariance = q;
    o.covariance = q * (i + 1);
    return o;
  }
  SightingsInput sightings(int i) const {
    std::map<int64_t, Eigen::Vector2d> landmarks;
    for (int k = 0; k < 8; ++k) landmarks[k] = 8 * Eigen::Vector2d(std::cos(k * M_PI / 4), std::sin(k * M_PI / 4));
    return test::sightings_at(robot, at(i), landmarks, 7);
  }
};

// The angle (rad) that best turns the landmarks of `b` onto those of `a` about their centroids (by id).
double landmarks_turned(const std::vector<SlamLandmark>& a, const std::vector<SlamLandmark>& b) {
  std::map<int64_t, Eigen::Vector2d> pa, pb;
  for (const auto& l : a) pa[l.id] = l.position.head<2>();
  for (const auto& l : b) pb[l.id] = l.position.head<2>();
  Eigen::Vector2d ca = Eigen::Vector2d::Zero(), cb = Eigen::Vector2d::Zero();
  int n = 0;
  for (const auto& [id, p] : pa)
    if (pb.contains(id)) ca += p, cb += pb[id], ++n;
  REQUIRE(n >= 3);
  ca /= n, cb /= n;
  double sin_sum = 0, cos_sum = 0;
  for (const auto& [id, p] : pa)
    if (pb.contains(id)) {
      const Eigen::Vector2d u = pb[id] - cb, v = p - ca;
      sin_sum += u.x() * v.y() - u.y() * v.x(), cos_sum += u.dot(v);
    }
  return std::atan2(sin_sum, cos_sum);
}

}  // namespace

TEST_CASE("slam graph: a lifelong thinning holds the map frame where the whole graph had it") {
  // The same run into lifelong graphs (budget 120 keyframes, 40 whole), with and without hold_frame, and a graph that
  // keeps everything.  The first keyframe sees no landmark; after a thinning its tie to the map is one composed
  // odometry edge, so a frame held by it is re-estimated from the biased odometry: the thinned map turns against the
  // whole one.
  SlamOptions life;
  life.lifelong.enabled = true;
  life.lifelong.planar = {120, 40};
  SlamOptions first = life;
  first.lifelong.hold_frame = false;
  SlamOptions full = life;
  full.lifelong.enabled = false;
  SlamGraph a(life), c(first), b(full);
  Recorder out_a, out_c, out_b;
  CircleRun run_a, run_c, run_b;
  double worst = 0, worst_first = 0;
  for (int i = 0; i < 320; ++i) {
    a.add_odometry("robot", run_a.odometry(i), out_a);
    c.add_odometry("robot", run_c.odometry(i), out_c);
    b.add_odometry("robot", run_b.odometry(i), out_b);
    if (i == 0) continue;
    a.add_sightings("robot", run_a.sightings(i), out_a);
    c.add_sightings("robot", run_c.sightings(i), out_c);
    b.add_sightings("robot", run_b.sightings(i), out_b);
    if (i % 10 != 0) continue;
    worst = std::max(worst, std::abs(landmarks_turned(b.landmarks("robot"), a.landmarks("robot"))));
    worst_first = std::max(worst_first, std::abs(landmarks_turned(b.landmarks("robot"), c.landmarks("robot"))));
  }
  CHECK(a.counters().thinnings >= 4);
  CHECK(c.counters().thinnings == a.counters().thinnings);
  CHECK(b.counters().thinnings == 0);
  MESSAGE("the thinned map turned at most " << worst * 180 / M_PI
                                            << " degrees against the whole one; held by the first "
                                            << "keyframe, " << worst_first * 180 / M_PI);
  // Held by the settled keyframe with the most ties: 0.0054 degrees; held by the first keyframe: 0.46.
  CHECK(worst < 0.1 * M_PI / 180);
  CHECK(worst_first > 0.2 * M_PI / 180);
}

TEST_CASE("slam graph: a loop that lands through thinned keyframes too uncertain to check is rejected") {
  // The circle run in a lifelong graph (budget 120 keyframes, 40 whole); a true loop from a time of its second lap,
  // whose keyframe was thinned, to the newest: it lands on the graph's keyframe before that time (not on a nearby
  // one through the time tolerance), uncertain by the composed odometry between them.  Accepted where that
  // uncertainty is allowed; rejected, and counted, where it is not, without the solve that the gate of an accepted
  // one needs first (the updates are held back by the solve period, and the newest keyframe is not solved yet).
  struct Outcome {
    SlamCounters counters;
    int64_t updates_for_loop = 0;
  };
  const auto run_with = [](double max_landing_sigma) {
    SlamOptions options;
    options.lifelong.enabled = true;
    options.lifelong.planar = {120, 40};
    options.loop_max_landing_sigma = max_landing_sigma;
    options.loop_time_tolerance_s = 0;  // a time lands on a keyframe of the graph only when it is that keyframe's
    options.solve_period_s = 3600;      // every update owed until something needs the estimate
    auto slam = std::make_unique<SlamGraph>(options);
    Recorder out;
    CircleRun run;
    for (int i = 0; i < 320; ++i) {
      slam->add_odometry("robot", run.odometry(i), out);
      if (i > 0) slam->add_sightings("robot", run.sightings(i), out);
    }
    REQUIRE(slam->counters().thinnings >= 1);
    LoopInput l;
    l.utime_from = test::odometry_at(run.robot, CircleRun::at(150)).utime;
    l.utime_to = test::odometry_at(run.robot, CircleRun::at(319)).utime;
    l.relative = (run.robot.truth(CircleRun::at(150)).inverse() * run.robot.truth(CircleRun::at(319))).to_se3();
    l.information = Matrix6d::Identity() * 100;
    const int64_t updates_before = slam->counters().updates;
    slam->add_loop("robot", l, out);
    REQUIRE(slam->counters().loops_on_thinned == 1);  // it did land through a thinned keyframe
    return Outcome{slam->counters(), slam->counters().updates - updates_before};
  };
  const Outcome allowed = run_with(100.0), refused = run_with(1e-3);
  CHECK(allowed.counters.loops_accepted == 1);
  CHECK(allowed.counters.loops_rejected == 0);
  CHECK(allowed.updates_for_loop > 0);
  CHECK(refused.counters.loops_accepted == 0);
  CHECK(refused.counters.loops_rejected == 1);
  CHECK(refused.updates_for_loop == 0);
}
