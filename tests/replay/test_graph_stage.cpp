// The graph back end as an engine stage: keyframes at the configured thresholds, proposals, loops answered by the
// simulated matcher bringing the keyframes close to the truth, a confident wrong loop rejected, and FUSED_POSE
// "graph" once per odometry message with strictly increasing times.
#include "daemon/engine/engine.hpp"
#include "daemon/engine/graph_pose_stage.hpp"
#include "daemon/engine/graph_stage.hpp"
#include "daemon/engine/pose_conversion.hpp"
#include "replay/simulated_matcher.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <stdexcept>

using namespace sextant;
using namespace sextant::engine;

namespace {

// A planar robot on a circle of radius 10 m at 1 m/s, odometry at 10 Hz whose heading noise makes it drift by metres
// (a random walk its increment covariance describes honestly), truth kept.
struct Run {
  std::vector<Odometry> odometry;
  std::vector<std::pair<int64_t, SE3>> truth;
};

Run circle_run(double seconds, uint64_t seed) {
  Run r;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0, 1);
  SE3 odom;
  SE3 prev_truth;
  for (int k = 0; k <= static_cast<int>(seconds * 10); ++k) {
    const double t = k * 0.1, a = t / 10.0;
    const SE3 truth(SO3(Eigen::Quaterniond(Eigen::AngleAxisd(a + M_PI / 2, Eigen::Vector3d::UnitZ()))),
                    Eigen::Vector3d(10 * std::cos(a), 10 * std::sin(a), 0));
    if (k > 0) {
      Vector6d xi = Vector6d::Zero();
      xi[0] = 0.01 * n(rng), xi[1] = 0.01 * n(rng), xi[5] = 0.006 * n(rng);
      odom = odom * prev_truth.inverse() * truth * SE3::exp(xi);
    } else {
      odom = truth;
    }
    prev_truth = truth;
    Odometry o;
    o.utime = 1'000'000 + k * 100'000;
    o.source = "robot";
    o.planar = true;
    o.pose = to_pose(odom);
    Matrix6 inc = Matrix6::Zero();
    inc(0, 0) = inc(1, 1) = 1e-4, inc(5, 5) = 3.6e-5;
    o.increment_covariance = inc;
    r.odometry.push_back(o);
    r.truth.emplace_back(o.utime, truth);
  }
  return r;
}

std::map<std::string, replay::MatcherTruth> matcher_truth(const Run& r) {
  std::map<std::string, replay::MatcherTruth> m;
  m["robot"].trajectory = replay::InterpolatedTrajectory(r.truth);
  m["robot"].planar = true;
  return m;
}

// An engine with dead reckoning and the graph back end only (keyframes every metre).
EngineConfig graph_only_config(bool propose_loops) {
  EngineConfig cfg;
  cfg.filter.type = "none";
  cfg.association.enabled = false;
  cfg.graph.keyframes.k1 = 1.0;  // a keyframe per metre
  cfg.graph.propose_loops = propose_loops;
  return cfg;
}

GraphStage& graph_stage_of(Engine& engine) {
  for (auto& s : engine.stages())
    if (s->name() == "graph") return dynamic_cast<GraphStage&>(*s);
  throw std::runtime_error("no graph stage");
}

int64_t counter(const Stage& s, const std::string& name) {
  for (const auto& [k, v] : s.counters())
    if (k == name) return v;
  return -1;
}

double keyframe_error(const GraphStage& g, const Run& r) {
  // RMS translation error of the keyframes against the truth at their times (the first keyframe is the truth).
  std::map<int64_t, SE3> truth(r.truth.begin(), r.truth.end());
  double s = 0;
  const auto kfs = g.keyframes("robot");
  for (const auto& k : kfs) s += (to_se3(k.pose).translation() - truth.at(k.utime).translation()).squaredNorm();
  return std::sqrt(s / static_cast<double>(kfs.size()));
}

}  // namespace

TEST_CASE("graph stage: keyframes by motion, proposals, loops from the simulated matcher correct the drift") {
  const Run run = circle_run(120, 3);  // two laps
  EngineConfig cfg = graph_only_config(true);
  cfg.graph.keyframes.k2 = 5.0;
  cfg.graph.proposals.n1 = 2;
  cfg.graph.proposals.seed = 9;
  Engine engine(cfg);
  GraphStage* graph = &graph_stage_of(engine);
  CHECK(engine.primary_estimator() == "graph");

  replay::SimulatedMatcherOptions mo;
  mo.seed = 5;
  replay::SimulatedMatcher matcher(matcher_truth(run), mo);
  std::vector<MatchRequest> requests;
  std::vector<FusedPose> fused;
  int trajectories = 0;
  const Emit emit = [&](Output out) {
    if (auto* r = std::get_if<MatchRequest>(&out)) requests.push_back(*r);
    if (auto* f = std::get_if<FusedPose>(&out); f && f->estimator == "graph") fused.push_back(*f);
    if (std::holds_alternative<Trajectory>(out)) ++trajectories;
  };
  double dead_reckoning_error = 0;
  for (const auto& o : run.odometry) {
    engine.handle(o, emit);
    // The front end answers every request at once (the replay order of a matcher on the bus).
    while (!requests.empty()) {
      const MatchRequest r = requests.front();
      requests.erase(requests.begin());
      if (auto answer = matcher.answer(r)) engine.handle(*answer, emit);
    }
  }
  // Dead reckoning's error at the same keyframe times, for comparison.
  {
    std::map<int64_t, SE3> odo, truth(run.truth.begin(), run.truth.end());
    for (const auto& o : run.odometry) odo[o.utime] = to_se3(o.pose);
    double s = 0;
    const auto kfs = graph->keyframes("robot");
    for (const auto& k : kfs) s += (odo.at(k.utime).translation() - truth.at(k.utime).translation()).squaredNorm();
    dead_reckoning_error = std::sqrt(s / static_cast<double>(kfs.size()));
  }
  const int64_t keyframes = counter(*graph, "keyframes");
  // 120 s at 1 m/s with k1 = 1 m: about one keyframe per metre travelled (the motion is measured on the drifting
  // odometry, so a little more).
  CHECK(keyframes >= 100);
  CHECK(keyframes <= 125);
  // n1 = 2 local + 4 random per keyframe once enough exist.
  CHECK(counter(*graph, "match_requests") >= 6 * (keyframes - 10));
  CHECK(counter(*graph, "loops_accepted") >= matcher.counts().answered * 9 / 10);
  CHECK(trajectories >= keyframes);
  const double err = keyframe_error(*graph, run);
  MESSAGE("keyframe RMS error " << err << " m, dead reckoning " << dead_reckoning_error << " m");
  CHECK(dead_reckoning_error > 0.5);  // the drift is real (fixed seed: 0.75 m)
  CHECK(err < 0.25 * dead_reckoning_error);
  // One fused pose per odometry message, strictly increasing in time.
  CHECK(fused.size() == run.odometry.size());
  for (size_t k = 1; k < fused.size(); ++k) CHECK(fused[k].utime > fused[k - 1].utime);
  CHECK(fused.back().covariance(0, 0) > 0);
}

TEST_CASE("graph stage: a confident wrong loop is rejected and leaves the map as it was, a time is bridged by odometry") {
  const Run run = circle_run(30, 4);
  Engine engine(graph_only_config(false));
  GraphStage* graph = &graph_stage_of(engine);
  const Emit ignore = [](Output) {};
  for (const auto& o : run.odometry) engine.handle(o, ignore);
  const auto before = graph->keyframes("robot");
  REQUIRE(before.size() > 20);

  // The truth between two keyframes, displaced by 5 m, with a 1 cm information: far outside the gate.
  std::map<int64_t, SE3> truth(run.truth.begin(), run.truth.end());
  LoopClosure wrong;
  wrong.utime = run.odometry.back().utime;
  wrong.source = "robot";
  wrong.planar = true;
  wrong.utime_from = before[2].utime;
  wrong.utime_to = before[20].utime;
  wrong.relative = to_pose(truth.at(wrong.utime_from).inverse() * truth.at(wrong.utime_to) * SE3(SO3(), Eigen::Vector3d(5, 0, 0)));
  wrong.information = Matrix6::Identity() * 1e4;
  engine.handle(wrong, ignore);
  CHECK(counter(*graph, "loops_rejected") == 1);
  CHECK(counter(*graph, "loops_accepted") == 0);
  const auto after = graph->keyframes("robot");
  for (size_t k = 0; k < before.size(); ++k) CHECK(before[k].pose.position.isApprox(after[k].pose.position));

  // A true loop stamped at odometry times between keyframes is moved onto the nearest keyframes and accepted.
  LoopClosure right = wrong;
  right.utime_from = before[2].utime + 100'000;
  right.utime_to = before[20].utime - 100'000;
  right.relative = to_pose(truth.at(right.utime_from).inverse() * truth.at(right.utime_to));
  engine.handle(right, ignore);
  CHECK(counter(*graph, "loops_accepted") == 1);
  // A loop at a time no odometry message had, or of an unknown body, is counted and dropped.
  right.utime_from += 7;
  engine.handle(right, ignore);
  CHECK(counter(*graph, "loops_unmatched") == 1);
  right.source = "nobody";
  engine.handle(right, ignore);
  CHECK(counter(*graph, "loops_unknown_source") == 1);
}

TEST_CASE("graph pose stage: odometry composed with the correction, never a utime at or before the last") {
  auto board = std::make_shared<GraphCorrections>();
  GraphPoseStage stage(board);
  std::vector<FusedPose> out;
  const Emit emit = [&](Output o) { out.push_back(std::get<FusedPose>(o)); };
  Odometry o;
  o.source = "r";
  o.planar = true;
  o.utime = 10;
  o.pose = to_pose(SE3(SO3(), Eigen::Vector3d(1, 0, 0)));
  stage.handle(o, emit);
  REQUIRE(out.size() == 1);
  CHECK(out[0].pose.position.isApprox(Eigen::Vector3d(1, 0, 0)));  // before any correction: the odometry frame
  GraphCorrection c;
  c.keyframe_odom = SE3(SO3(), Eigen::Vector3d(1, 0, 0));
  c.keyframe_map = SE3(SO3(Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()))), Eigen::Vector3d(0, 5, 0));
  c.keyframe_covariance = Matrix6::Identity() * 0.01;
  board->set("r", c);
  o.utime = 20;
  o.pose = to_pose(SE3(SO3(), Eigen::Vector3d(3, 0, 0)));  // 2 m ahead of the keyframe in odometry
  stage.handle(o, emit);
  REQUIRE(out.size() == 2);
  CHECK(out[1].pose.position.isApprox(Eigen::Vector3d(0, 7, 0), 1e-12));  // 2 m along the corrected heading
  CHECK(out[1].covariance(1, 1) > 0.01);  // the keyframe's uncertainty, grown by the lever arm
  o.utime = 20;
  stage.handle(o, emit);
  o.utime = 15;
  stage.handle(o, emit);
  CHECK(out.size() == 2);
  CHECK(stage.counters()[1].second == 2);  // out_of_order
}

TEST_CASE("graph stage: a loop about a time the odometry has not reached waits for it") {
  const Run run = circle_run(30, 4);
  Engine engine(graph_only_config(false));
  GraphStage* graph = &graph_stage_of(engine);
  const Emit ignore = [](Output) {};
  std::map<int64_t, SE3> truth(run.truth.begin(), run.truth.end());
  for (size_t k = 0; k < 100; ++k) engine.handle(run.odometry[k], ignore);
  LoopClosure early;
  early.utime = run.odometry[99].utime;
  early.source = "robot";
  early.planar = true;
  early.utime_from = run.odometry[20].utime;
  early.utime_to = run.odometry[150].utime;  // the odometry is at 99: the loop is early (as the simulator writes it)
  early.relative = to_pose(truth.at(early.utime_from).inverse() * truth.at(early.utime_to));
  early.information = Matrix6::Identity() * 1e4;
  engine.handle(early, ignore);
  CHECK(counter(*graph, "loops_accepted") == 0);
  CHECK(counter(*graph, "loops_unmatched") == 0);
  for (size_t k = 100; k < run.odometry.size(); ++k) engine.handle(run.odometry[k], ignore);
  CHECK(counter(*graph, "loops_accepted") == 1);
  CHECK(counter(*graph, "loops_unmatched") == 0);
}
