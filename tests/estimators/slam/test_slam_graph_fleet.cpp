// The SLAM layer's fleet from plain C++: two robots, each with odometry that starts at the origin of its own frame,
// join one map frame through shared landmarks or through sightings of each other, and then hold each other's
// poses where the truth puts them; maps that only look alike (the same landmark ids at unrelated places) stay apart;
// an inter-robot loop and the frames survive a state saved and restored.
#include "estimators/lie/se2.hpp"
#include "estimators/slam/slam_graph.hpp"
#include "estimators/slam/fleet_scenario.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <random>

using namespace sextant;
using namespace sextant::slam;
using namespace sextant::slam::test;

namespace {

/// Drives both robots for `seconds` (odometry at 10 Hz, sightings at 5 Hz), robot b seeing `b_world`.
void drive(SlamGraph& slam, const Robot& a, const Robot& b, const std::map<int64_t, Eigen::Vector2d>& a_world,
           const std::map<int64_t, Eigen::Vector2d>& b_world, double seconds, bool see_each_other = false) {
  Quiet out;
  for (int i = 0; i <= static_cast<int>(seconds * 10); ++i) {
    const double t = 0.1 * i;
    slam.add_odometry(a.name, odometry_at(a, t), out);
    slam.add_odometry(b.name, odometry_at(b, t), out);
    if (i % 2 != 0) continue;
    auto sa = sightings_at(a, t, a_world);
    auto sb = sightings_at(b, t, b_world);
    if (see_each_other) {  // each robot's origin as a marker: a is 1001, b is 1000
      const auto more_a = sightings_at(a, t, {{1000, b.truth(t).translation()}});
      const auto more_b = sightings_at(b, t, {{1001, a.truth(t).translation()}});
      sa.sightings.insert(sa.sightings.end(), more_a.sightings.begin(), more_a.sightings.end());
      sb.sightings.insert(sb.sightings.end(), more_b.sightings.begin(), more_b.sightings.end());
    }
    slam.add_sightings(a.name, sa, out);
    slam.add_sightings(b.name, sb, out);
  }
}

/// The largest distance between b's keyframes and the truth, expressed in a's frame (a's pose at t = 0).
double worst_in_frame_of(const SlamGraph& slam, const Robot& a, const Robot& b) {
  double worst = 0;
  for (const KeyframeEstimate& k : slam.keyframes(b.name)) {
    const double t = static_cast<double>(k.utime - 1000000) / 1e6;
    const SE3 truth = (a.truth(0).inverse() * b.truth(t)).to_se3();
    worst = std::max(worst, (k.pose.translation() - truth.translation()).norm());
  }
  return worst;
}

SlamOptions fleet_options() {
  SlamOptions o;
  o.propose_loops = false;
  o.fleet.markers = {{1000, "b"}, {1001, "a"}};
  return o;
}

}  // namespace

TEST_CASE("fleet: two robots whose maps share landmarks join one frame, and b's poses land where the truth has them") {
  const Robot a{"a", {0, 0}, 3, 0, 0.3}, b{"b", {0.5, 0.5}, 2.5, 2.0, -0.25};
  const auto world = random_landmarks(1, 25);
  SlamGraph slam(fleet_options());
  drive(slam, a, b, world, world, 20);
  CHECK(slam.counters().fleet_joins == 1);
  CHECK(slam.frame_of("a") == "a");
  CHECK(slam.frame_of("b") == "a");  // the frame whose root name comes first stays
  CHECK(slam.frames().size() == 1);
  CHECK(worst_in_frame_of(slam, a, b) < 0.02);
  // One map: each landmark id once, seen by both.
  CHECK(slam.landmarks("a").size() == slam.landmarks("b").size());
  CHECK(slam.graph_landmarks() <= static_cast<int64_t>(world.size()));
}

TEST_CASE("fleet: robots that see each other join through those sightings alone, and keep them as factors") {
  const Robot a{"a", {0, 0}, 3, 0, 0.3}, b{"b", {0.5, 0.5}, 2.5, 2.0, -0.25};
  SlamGraph slam(fleet_options());
  // Disjoint landmark ids: no landmark is shared.
  auto world_b = random_landmarks(1, 25);
  std::map<int64_t, Eigen::Vector2d> ids_b;
  for (const auto& [id, p] : world_b) ids_b[id + 500] = p;
  drive(slam, a, b, random_landmarks(1, 25), ids_b, 20, true);
  CHECK(slam.counters().fleet_joins == 1);
  CHECK(slam.frame_of("b") == "a");
  CHECK(slam.counters().fleet_sightings > 10);
  CHECK(worst_in_frame_of(slam, a, b) < 0.05);
}

TEST_CASE("fleet: maps that only look alike (the same landmark ids at unrelated places) are never folded together") {
  const Robot a{"a", {0, 0}, 3, 0, 0.3}, b{"b", {0.5, 0.5}, 2.5, 2.0, -0.25};
  SlamGraph slam(fleet_options());
  drive(slam, a, b, random_landmarks(1, 25), random_landmarks(2, 25), 20);
  CHECK(slam.counters().fleet_joins == 0);
  CHECK(slam.frames().size() == 2);
  CHECK(slam.frame_of("b") == "b");
}

TEST_CASE("fleet: disabled, the robots stay apart whatever they share") {
  const Robot a{"a", {0, 0}, 3, 0, 0.3}, b{"b", {0.5, 0.5}, 2.5, 2.0, -0.25};
  SlamOptions o = fleet_options();
  o.fleet.enabled = false;
  SlamGraph slam(o);
  const auto world = random_landmarks(1, 25);
  drive(slam, a, b, world, world, 10, true);
  CHECK(slam.frames().size() == 2);
  CHECK(slam.counters().fleet_sightings == 0);
}

TEST_CASE(
    "fleet: an inter-robot loop joins with agreeing sightings, a fleet state saved and restored continues bit for "
    "bit") {
  const Robot a{"a", {0, 0}, 3, 0, 0.3}, b{"b", {0.5, 0.5}, 2.5, 2.0, -0.25};
  SlamGraph slam(fleet_options());
  auto world_b = random_landmarks(1, 25);
  std::map<int64_t, Eigen::Vector2d> ids_b;
  for (const auto& [id, p] : world_b) ids_b[id + 500] = p;
  drive(slam, a, b, random_landmarks(1, 25), ids_b, 4, true);
  Quiet out;
  // A loop from a at t = 2 s to b at t = 3 s, the truth's relative pose.
  LoopInput l;
  l.utime_from = 3000000, l.utime_to = 4000000;
  l.relative = (a.truth(2).inverse() * b.truth(3)).to_se3();
  l.information = Matrix6d::Identity() * 1e4;
  l.body_to = "b";
  slam.add_loop("a", l, out);
  CHECK(slam.frame_of("b") == "a");
  archive::ArchiveWriter w;
  slam.save(w);
  SlamGraph restored(fleet_options());
  archive::ArchiveReader r(w.data().data(), w.data().size(), "test");
  restored.load(r);
  CHECK(restored.frame_of("b") == "a");
  for (int i = 41; i < 60; ++i) {
    for (SlamGraph* s : {&slam, &restored}) {
      s->add_odometry("a", odometry_at(a, 0.1 * i), out);
      s->add_odometry("b", odometry_at(b, 0.1 * i), out);
    }
  }
  const auto ka = slam.keyframes("b"), kb = restored.keyframes("b");
  REQUIRE(ka.size() == kb.size());
  for (size_t k = 0; k < ka.size(); ++k) CHECK(ka[k].pose.translation() == kb[k].pose.translation());
}

TEST_CASE("fleet: once two robots share a frame, their new keyframes are proposed against each other's nearest") {
  struct Proposals final : SlamListener {
    int fleet = 0;
    double farthest = 0;
    void updated(const std::string&, int64_t, const graph::IncrementalStatus&) override {}
    void loop_proposed(const std::string&, int64_t, const KeyframeEstimate&, const KeyframeEstimate&, bool) override {}
    void fleet_loop_proposed(const std::string& body, int64_t, const KeyframeEstimate& a, const std::string& other,
                             const KeyframeEstimate& b) override {
      CHECK(body != other);
      farthest = std::max(farthest, (a.pose.translation() - b.pose.translation()).norm());
      ++fleet;
    }
  };
  const Robot a{"a", {0, 0}, 3, 0, 0.3}, b{"b", {0.5, 0.5}, 2.5, 2.0, -0.25};
  SlamOptions o = fleet_options();
  o.propose_loops = true;
  SlamGraph slam(o);
  const auto world = random_landmarks(1, 25);
  drive(slam, a, b, world, world, 10);
  REQUIRE(slam.frame_of("b") == "a");
  Proposals out;
  for (int i = 101; i < 160; ++i) {
    slam.add_odometry("a", odometry_at(a, 0.1 * i), out);
    slam.add_odometry("b", odometry_at(b, 0.1 * i), out);
  }
  CHECK(out.fleet > 10);
  CHECK(out.farthest <= o.fleet.proposal_radius);
}
