// The graph back end as an engine stage: keyframes at the configured thresholds, proposals, loops answered by the
// simulated matcher bringing the keyframes close to the truth, a confident wrong loop rejected, and FUSED_POSE
// "graph" once per odometry message with strictly increasing times; landmark sightings mapping the landmarks and
// holding the keyframes near the truth, mis-identified sightings stopped by the gate (and by the robust kernel when
// the gate is open), a 3-D body mapping 3-D landmarks, and the sightings the stage cannot use counted.
#include "assoc/chi_square.hpp"
#include "daemon/stage_counters.hpp"
#include "daemon/engine/engine.hpp"
#include "daemon/engine/graph_pose_stage.hpp"
#include "daemon/engine/graph_stage.hpp"
#include "daemon/engine/pose_conversion.hpp"
#include "daemon/engine/trajectory_rebuild.hpp"
#include "sim/simulated_matcher.hpp"
#include "eval/trajectory_eval.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <optional>
#include <random>
#include <stdexcept>
#include <utility>

using namespace sextant;
using namespace sextant::engine;

using sextant::stage_counters::counter;

namespace {

// A planar robot on a circle of radius 10 m at 1 m/s, odometry at 10 Hz whose heading noise makes it drift by metres
// (a random walk its increment covariance describes honestly), truth kept.
struct Run {
  std::vector<Odometry> odometry;
  std::vector<std::pair<int64_t, SE3>> truth;
};

// The true pose t seconds into the run.
SE3 circle_truth(double t) {
  const double a = t / 10.0;
  return SE3(SO3(Eigen::Quaterniond(Eigen::AngleAxisd(a + M_PI / 2, Eigen::Vector3d::UnitZ()))),
             Eigen::Vector3d(10 * std::cos(a), 10 * std::sin(a), 0));
}

// rate_hz: odometry messages per second (the noise per message scaled so that the drift per second stays the same).
Run circle_run(double seconds, uint64_t seed, int rate_hz = 10, const std::string& source = "robot") {
  Run r;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0, 1);
  const double dt = 1.0 / rate_hz, scale = std::sqrt(10.0 / rate_hz);
  SE3 odom;
  SE3 prev_truth;
  for (int k = 0; k <= static_cast<int>(seconds * rate_hz); ++k) {
    const SE3 truth = circle_truth(k * dt);
    if (k > 0) {
      Vector6d xi = Vector6d::Zero();
      xi[0] = 0.01 * scale * n(rng), xi[1] = 0.01 * scale * n(rng), xi[5] = 0.006 * scale * n(rng);
      odom = odom * prev_truth.inverse() * truth * SE3::exp(xi);
    } else {
      odom = truth;
    }
    prev_truth = truth;
    Odometry o;
    o.utime = 1'000'000 + k * (1'000'000 / rate_hz);
    o.source = source;
    o.planar = true;
    o.pose = to_pose(odom);
    Matrix6 inc = Matrix6::Zero();
    inc(0, 0) = inc(1, 1) = 1e-4 * scale * scale, inc(5, 5) = 3.6e-5 * scale * scale;
    o.increment_covariance = inc;
    r.odometry.push_back(o);
    r.truth.emplace_back(o.utime, truth);
  }
  return r;
}

// The circle run as 3-D odometry: each planar increment with a little noise in z, roll and pitch on top (and the
// increment covariance saying so); the truth stays the planar one.
Run spatial_run(Run run, uint64_t seed) {
  std::vector<SE3> planar;
  for (const auto& o : run.odometry) planar.push_back(to_se3(o.pose));
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0, 1);
  SE3 odom = planar.front();
  for (size_t k = 0; k < run.odometry.size(); ++k) {
    Odometry& o = run.odometry[k];
    if (k > 0) {
      Vector6d xi = Vector6d::Zero();
      xi[2] = 0.002 * n(rng), xi[3] = 0.001 * n(rng), xi[4] = 0.001 * n(rng);
      odom = odom * planar[k - 1].inverse() * planar[k] * SE3::exp(xi);
    }
    o.planar = false;
    o.pose = to_pose(odom);
    Matrix6 inc = *o.increment_covariance;
    inc(2, 2) = 4e-6, inc(3, 3) = inc(4, 4) = 1e-6;
    o.increment_covariance = inc;
  }
  return run;
}

// Twelve landmarks around the circle (ids 100..111, 3 m inside and outside it), seen from the run at 2 Hz, 50 ms after
// an odometry message (between two of them), within 6 m; range sigma 5 cm, bearing sigma 0.02 rad.
std::vector<Eigen::Vector3d> ring_landmarks() {
  std::vector<Eigen::Vector3d> out;
  for (int i = 0; i < 12; ++i) {
    const double a = i * M_PI / 6, r = i % 2 ? 13.0 : 7.0;
    out.emplace_back(r * std::cos(a), r * std::sin(a), 0);
  }
  return out;
}

LandmarkObservation sighting_of(const SE3& pose, const Eigen::Vector3d& landmark, int64_t id, bool planar = true) {
  const Eigen::Vector3d l = pose.inverse() * landmark;
  LandmarkObservation ob;
  ob.id = id;
  ob.range = planar ? std::hypot(l.x(), l.y()) : l.norm();
  ob.azimuth = std::atan2(l.y(), l.x());
  ob.elevation = planar ? 0.0 : std::atan2(l.z(), std::hypot(l.x(), l.y()));
  ob.covariance = Eigen::Vector3d(0.05 * 0.05, 0.02 * 0.02, planar ? 0.0 : 0.02 * 0.02).asDiagonal();
  return ob;
}

std::vector<LandmarkSightings> ring_sightings(const Run& run, uint64_t seed, bool planar = true) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0, 1);
  auto landmarks = ring_landmarks();
  if (!planar)
    for (size_t i = 0; i < landmarks.size(); ++i) landmarks[i].z() = i % 3 == 0 ? 1.0 : i % 3 == 1 ? -0.5 : 2.0;
  std::vector<LandmarkSightings> out;
  for (size_t k = 0; k + 1 < run.odometry.size(); k += 5) {
    LandmarkSightings s;
    s.utime = run.odometry[k].utime + 50'000;
    s.source = "robot";
    s.planar = planar;
    const SE3 truth = circle_truth(static_cast<double>(s.utime - run.odometry.front().utime) * 1e-6);
    for (size_t i = 0; i < landmarks.size(); ++i) {
      if ((truth.inverse() * landmarks[i]).norm() > 6.0) continue;
      LandmarkObservation ob = sighting_of(truth, landmarks[i], 100 + static_cast<int64_t>(i), planar);
      ob.range += 0.05 * n(rng);
      ob.azimuth += 0.02 * n(rng);
      if (!planar) ob.elevation += 0.02 * n(rng);
      s.observations.push_back(ob);
    }
    if (!s.observations.empty()) out.push_back(s);
  }
  return out;
}

// Odometry and sightings merged in time order (at equal times the odometry first, as the converters write them).
void feed(Engine& engine, const Run& run, const std::vector<LandmarkSightings>& sightings, const Emit& emit) {
  size_t j = 0;
  for (const auto& o : run.odometry) {
    for (; j < sightings.size() && sightings[j].utime < o.utime; ++j) engine.handle(sightings[j], emit);
    engine.handle(o, emit);
  }
  for (; j < sightings.size(); ++j) engine.handle(sightings[j], emit);
}

std::map<std::string, tools::MatcherTruth> matcher_truth(const Run& r) {
  std::map<std::string, tools::MatcherTruth> m;
  m["robot"].trajectory = tools::InterpolatedTrajectory(r.truth);
  m["robot"].planar = true;
  return m;
}

// An engine with dead reckoning and the graph back end only (keyframes every metre).
EngineConfig graph_only_config(bool propose_loops) {
  EngineConfig cfg;
  cfg.filter.type = FilterType::kNone;
  cfg.association.enabled = false;
  cfg.graph.keyframes.k1 = 1.0;  // a keyframe per metre
  cfg.graph.propose_loops = propose_loops;
  return cfg;
}

GraphStage& graph_stage_of(Engine& engine) {
  for (auto& s : engine.stages())
    if (s->kind() == StageKind::kGraph) return dynamic_cast<GraphStage&>(*s);
  throw std::runtime_error("no graph stage");
}

double keyframe_error(const GraphStage& g, const Run& r) {
  // RMS translation error of the keyframes against the truth at their times (the first keyframe is the truth).
  std::map<int64_t, SE3> truth(r.truth.begin(), r.truth.end());
  double s = 0;
  const auto kfs = g.keyframes("robot");
  for (const auto& k : kfs) s += (to_se3(k.pose).translation() - truth.at(k.utime).translation()).squaredNorm();
  return std::sqrt(s / static_cast<double>(kfs.size()));
}

// ATE as `sextant eval` computes it (rigid alignment) of the keyframes and of dead reckoning at the same times.
std::pair<tools::AteResult, tools::AteResult> keyframe_and_dead_reckoning_ate(const GraphStage& g, const Run& run) {
  std::map<int64_t, SE3> truth(run.truth.begin(), run.truth.end()), odo;
  for (const auto& o : run.odometry) odo[o.utime] = to_se3(o.pose);
  std::vector<tools::StampedPose> gt, est, dr;
  for (const auto& k : g.keyframes("robot")) {
    const double t = static_cast<double>(k.utime) * 1e-6;
    gt.push_back({t, to_pose(truth.at(k.utime))});
    est.push_back({t, k.pose});
    dr.push_back({t, to_pose(odo.at(k.utime))});
  }
  return {tools::absolute_trajectory_error(gt, est), tools::absolute_trajectory_error(gt, dr)};
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

  tools::SimulatedMatcherOptions mo;
  mo.seed = 5;
  tools::SimulatedMatcher matcher(matcher_truth(run), mo);
  std::vector<MatchRequest> requests;
  std::vector<FusedPose> fused;
  std::vector<Trajectory> trajectories;
  const Emit emit = [&](Output out) {
    if (auto* r = std::get_if<MatchRequest>(&out)) requests.push_back(*r);
    if (auto* f = std::get_if<FusedPose>(&out); f && f->estimator == "graph") fused.push_back(*f);
    if (auto* t = std::get_if<Trajectory>(&out)) trajectories.push_back(*t);
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
  // TRAJECTORY: rebuilt as the .lcm file tells a subscriber (updates replace keyframes by id, removed ids go, a
  // snapshot chunk is authoritative for its id range), it equals the stage's keyframes exactly after the final flush;
  // publications are at most 1 Hz of data time and every message is small.
  engine.finish(emit);
  REQUIRE(!trajectories.empty());
  TrajectoryRebuild rebuild;
  std::set<int64_t> publication_times;
  for (const Trajectory& t : trajectories) {
    CHECK(t.keyframes.size() <= 512);
    publication_times.insert(t.utime);
    rebuild.add(t);
  }
  const auto final_keyframes = graph->keyframes("robot");
  const auto& rebuilt = rebuild.keyframes();
  REQUIRE(rebuilt.size() == final_keyframes.size());
  CHECK(rebuild.total_keyframes() == static_cast<int>(final_keyframes.size()));
  for (const Keyframe& k : final_keyframes) {
    REQUIRE(rebuilt.count(k.id) == 1);
    CHECK(rebuilt.at(k.id).utime == k.utime);
    CHECK(rebuilt.at(k.id).pose.position == k.pose.position);
    CHECK(rebuilt.at(k.id).pose.orientation.coeffs() == k.pose.orientation.coeffs());
  }
  // 120 s of data at 1 Hz, and the final flush (at the last publication's time or later).
  CHECK(publication_times.size() <= 122);
  for (auto it = publication_times.begin();
       std::next(it) != publication_times.end() && std::next(it, 2) != publication_times.end(); ++it)
    CHECK(*std::next(it) - *it >= 1'000'000);
  const double err = keyframe_error(*graph, run);
  MESSAGE("keyframe RMS error " << err << " m, dead reckoning " << dead_reckoning_error << " m");
  CHECK(dead_reckoning_error > 0.5);  // the drift is real (fixed seed: 0.75 m)
  CHECK(err < 0.25 * dead_reckoning_error);
  // One fused pose per odometry message, strictly increasing in time.
  CHECK(fused.size() == run.odometry.size());
  for (size_t k = 1; k < fused.size(); ++k) CHECK(fused[k].utime > fused[k - 1].utime);
  CHECK(fused.back().covariance(0, 0) > 0);
}

TEST_CASE("graph stage: the default kernel width keeps true loops at full weight, planar and 3-D bodies alike") {
  // Two bodies in one stage, a planar one and a 3-D one, loops answered from the truth (no wrong answers).  With the
  // default width ("auto": chi2 quantile of the loop's dimension at the gate's 0.999) a true loop's chi2 stays below
  // phi and keeps weight 1 (but for a few per mille); with phi = 1 most true loops are down-weighted, 3-D ones most
  // (P(chi2_3 > 1) = 0.80, P(chi2_6 > 1) = 0.99).
  const Run flat = circle_run(60, 3, 10, "flat");
  const Run spatial = spatial_run(circle_run(60, 4, 10, "spatial"), 22);
  std::map<std::string, tools::MatcherTruth> truth;
  truth["flat"] = {tools::InterpolatedTrajectory(flat.truth), true};
  truth["spatial"] = {tools::InterpolatedTrajectory(spatial.truth), false};
  // Each smoother's kernel width, and the fraction of its loops with a weight below 1 at the end of the run.
  auto run_with = [&](std::optional<double> width) {
    EngineConfig cfg = graph_only_config(true);
    cfg.graph.kernel_width = width;
    Engine engine(cfg);
    tools::SimulatedMatcher matcher(truth, tools::SimulatedMatcherOptions{});
    std::vector<MatchRequest> requests;
    const Emit emit = [&](Output out) {
      if (auto* r = std::get_if<MatchRequest>(&out)) requests.push_back(*r);
    };
    for (size_t k = 0; k < flat.odometry.size(); ++k) {
      engine.handle(flat.odometry[k], emit);
      engine.handle(spatial.odometry[k], emit);
      for (const MatchRequest& r : std::exchange(requests, {}))
        if (auto answer = matcher.answer(r)) engine.handle(*answer, emit);
    }
    const GraphStage& g = graph_stage_of(engine);
    CHECK(counter(g, "loops_rejected") <= counter(g, "loops_accepted") / 100);  // the gate: 0.1 % of true loops
    std::map<bool, std::pair<double, double>> out;  // planar -> (kernel width, fraction down-weighted)
    for (const bool planar : {true, false}) {
      const graph::IncrementalSmoother* sm = g.smoother(planar);
      REQUIRE(sm != nullptr);
      int loops = 0, weak = 0;
      for (size_t f = 0; f < sm->graph().factors().size(); ++f) {
        // Loops between keyframes that are not consecutive (odometry edges join consecutive ones; one body per
        // smoother and no landmarks here, so consecutive keyframes have consecutive variable indices).
        const auto& v = sm->graph().factors()[f]->variables();
        if (v.size() != 2 || std::abs(v[1] - v[0]) == 1) continue;
        ++loops;
        weak += sm->robust_weight_of(f) < 0.999 ? 1 : 0;
      }
      REQUIRE(loops > 100);
      out[planar] = {sm->options().kernel_width, static_cast<double>(weak) / loops};
    }
    return out;
  };
  const auto by_default = run_with(std::nullopt), phi1 = run_with(1.0);
  MESSAGE("down-weighted true loops, auto: planar " << by_default.at(true).second << ", 3-D "
                                                    << by_default.at(false).second << "; phi = 1: planar "
                                                    << phi1.at(true).second << ", 3-D " << phi1.at(false).second);
  CHECK(by_default.at(true).first == doctest::Approx(16.266).epsilon(0.02));   // chi2_3(0.999), as the gate computes it
  CHECK(by_default.at(false).first == doctest::Approx(22.458).epsilon(0.02));  // chi2_6(0.999)
  CHECK(by_default.at(true).second < 0.02);
  CHECK(by_default.at(false).second < 0.02);
  CHECK(phi1.at(true).first == 1.0);
  CHECK(phi1.at(true).second > 0.5);
  CHECK(phi1.at(false).second > 0.8);
}

TEST_CASE(
    "graph stage: a confident wrong loop is rejected and leaves the map as it was, a time is bridged by odometry") {
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
  wrong.relative =
      to_pose(truth.at(wrong.utime_from).inverse() * truth.at(wrong.utime_to) * SE3(SO3(), Eigen::Vector3d(5, 0, 0)));
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

TEST_CASE("graph pose stage: odometry composed with the correction") {
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
  c.keyframe_map =
      SE3(SO3(Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()))), Eigen::Vector3d(0, 5, 0));
  c.keyframe_covariance = Matrix6::Identity() * 0.01;
  board->set("r", c);
  o.utime = 20;
  o.pose = to_pose(SE3(SO3(), Eigen::Vector3d(3, 0, 0)));  // 2 m ahead of the keyframe in odometry
  stage.handle(o, emit);
  REQUIRE(out.size() == 2);
  CHECK(out[1].pose.position.isApprox(Eigen::Vector3d(0, 7, 0), 1e-12));  // 2 m along the corrected heading
  CHECK(out[1].covariance(1, 1) > 0.01);  // the keyframe's uncertainty, grown by the lever arm
  // A repeated or earlier time is the intake's and the publisher's to refuse (test_publisher.cpp): the stage composes.
  o.utime = 15;
  stage.handle(o, emit);
  CHECK(out.size() == 3);
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

TEST_CASE("graph stage: landmark sightings with ids map the landmarks and hold the keyframes to the truth") {
  const Run run = circle_run(120, 3);  // two laps, no loop closures
  const auto sightings = ring_sightings(run, 11);
  Engine engine(graph_only_config(false));
  GraphStage* graph = &graph_stage_of(engine);
  int trajectories = 0;
  const Emit emit = [&](Output out) { trajectories += std::holds_alternative<Trajectory>(out) ? 1 : 0; };
  feed(engine, run, sightings, emit);

  size_t observations = 0;
  for (const auto& s : sightings) observations += s.observations.size();
  REQUIRE(observations > 300);
  CHECK(counter(*graph, "landmarks") == 12);
  // Every true sighting passes the gate (0.999 each: at most a handful rejected), none waits or is lost.
  CHECK(counter(*graph, "sightings_accepted") >= static_cast<int64_t>(observations) - 5);
  CHECK(counter(*graph, "sightings_accepted") + counter(*graph, "sightings_rejected") ==
        static_cast<int64_t>(observations));
  CHECK(counter(*graph, "sightings_unmatched") == 0);
  CHECK(counter(*graph, "updates") >= static_cast<int64_t>(sightings.size()));  // one optimization per sighting message
  CHECK(trajectories > 0);

  // ATE as `sextant eval` computes it (rigid alignment: the map's rotation about the fixed first keyframe is only as
  // good as the first sightings' bearings, a gauge the alignment takes out) of the keyframes and of dead reckoning
  // at the same times.
  const auto [ate, ate_dr] = keyframe_and_dead_reckoning_ate(*graph, run);
  MESSAGE("keyframe ATE " << ate.error.rmse << " m, dead reckoning " << ate_dr.error.rmse << " m");
  CHECK(ate_dr.error.rmse > 0.3);  // the drift is real
  CHECK(ate.error.rmse < 0.2 * ate_dr.error.rmse);
  // The landmarks where they are, in the same alignment.
  const auto ring = ring_landmarks();
  const auto mapped = graph->landmarks("robot");
  REQUIRE(mapped.size() == 12);
  for (const auto& l : mapped) {
    const Eigen::Vector3d aligned = ate.rotation * l.position + ate.translation;
    CHECK((aligned - ring[static_cast<size_t>(l.id - 100)]).norm() < 0.15);
    CHECK(l.sightings > 5);
  }
}

TEST_CASE("graph stage: sightings of a mis-identified landmark are rejected and do not bend the map") {
  const Run run = circle_run(60, 4);
  const auto sightings = ring_sightings(run, 12);
  const Emit ignore = [](Output) {};
  // The same run with, every second of its second half, one more observation: a landmark in view reported under the
  // id of landmark 101 (at 30 degrees on the ring, mapped in the first half, now more than 15 m away).
  std::vector<LandmarkSightings> with_wrong = sightings;
  int wrong = 0;
  for (auto& s : with_wrong) {
    if (s.utime > run.odometry.front().utime + 30'000'000 && (s.utime / 500'000) % 2 == 0) {
      LandmarkObservation ob = s.observations.front();
      ob.id = 101;
      s.observations.push_back(ob);
      ++wrong;
    }
  }
  REQUIRE(wrong >= 20);
  auto run_with = [&](const std::vector<LandmarkSightings>& input, double gate_odometry_scale, bool robust,
                      std::optional<double> phi = 1.0) {
    EngineConfig cfg = graph_only_config(false);
    cfg.graph.landmarks.gate_odometry_scale = gate_odometry_scale;
    cfg.graph.landmarks.robust = robust;
    cfg.graph.kernel_width = phi;
    auto engine = std::make_unique<Engine>(cfg);
    feed(*engine, run, input, ignore);
    return engine;
  };
  auto largest_shift = [](const GraphStage& a, const GraphStage& b) {
    double moved = 0;
    const auto ka = a.keyframes("robot"), kb = b.keyframes("robot");
    REQUIRE(ka.size() == kb.size());
    for (size_t k = 0; k < ka.size(); ++k) moved = std::max(moved, (ka[k].pose.position - kb[k].pose.position).norm());
    const auto la = a.landmarks("robot"), lb = b.landmarks("robot");
    REQUIRE(la.size() == lb.size());
    for (size_t k = 0; k < la.size(); ++k) moved = std::max(moved, (la[k].position - lb[k].position).norm());
    return moved;
  };

  // The gate (default settings) rejects every wrong sighting: the map is the clean run's.
  const auto clean = run_with(sightings, 3.0, true), dirty = run_with(with_wrong, 3.0, true);
  const GraphStage& gc = graph_stage_of(*clean);
  const GraphStage& gd = graph_stage_of(*dirty);
  CHECK(counter(gd, "sightings_rejected") == counter(gc, "sightings_rejected") + wrong);
  CHECK(counter(gd, "landmarks") == counter(gc, "landmarks"));
  CHECK(largest_shift(gc, gd) < 1e-9);

  // With the gate opened wide (odometry standard deviations x 1000) the wrong sightings reach the smoother: the
  // robust kernel (DCS, phi = 5) keeps the map within a centimetre of the clean run's; without it, it is bent by
  // metres.  (With phi = 1 DCS also down-weights true 2-D sightings, chi2 about 2, by a weight that depends on
  // where each was last linearized: two runs then differ by decimetres, kernel or not.)
  const auto open_robust = run_with(with_wrong, 1000, true, 5.0), open_plain = run_with(with_wrong, 1000, false);
  const auto clean_robust = run_with(sightings, 1000, true, 5.0), clean_plain = run_with(sightings, 1000, false);
  CHECK(counter(graph_stage_of(*open_robust), "sightings_rejected") == 0);
  const double with_kernel = largest_shift(graph_stage_of(*clean_robust), graph_stage_of(*open_robust));
  const double without = largest_shift(graph_stage_of(*clean_plain), graph_stage_of(*open_plain));
  MESSAGE("map moved by the wrong sightings past an open gate: " << with_kernel << " m with DCS, " << without
                                                                 << " m without");
  CHECK(with_kernel < 0.02);
  CHECK(without > 0.3);

  // With the default width (auto) the sightings bring their own to the smoother: the sighting gate's chi-square
  // quantile of their dimension (2: range, bearing), not the planar loops' (3 dof).  Every sighting factor's weight is
  // DCS's at that width, k^2 with k = min(1, 2 phi / (phi + chi2)) at its linearization point; the wrong ones, far out,
  // would have kept more weight at the loops' width.
  const auto open_auto = run_with(with_wrong, 1000, true, std::nullopt);
  const GraphConfig& auto_config = graph_only_config(false).graph;
  const double phi_sighting = assoc::chi2_quantile(2, auto_config.landmarks.gate_probability);
  const double phi_loop = assoc::chi2_quantile(3, auto_config.loop_gate_probability);
  REQUIRE(sighting_kernel_width_for(auto_config, true) == phi_sighting);
  REQUIRE(kernel_width_for(auto_config, true) == phi_loop);
  REQUIRE(phi_sighting < phi_loop - 2);
  const graph::IncrementalSmoother& sm = *graph_stage_of(*open_auto).smoother(true);
  auto dcs = [](double phi, double chi2) { return std::pow(std::min(1.0, 2 * phi / (phi + chi2)), 2); };
  int sightings_in_graph = 0, heavier_at_loop_width = 0;
  for (size_t i = 0; i < sm.graph().factors().size(); ++i) {
    const graph::Factor& f = *sm.graph().factors()[i];
    if (dynamic_cast<const graph::PointObservationFactor*>(&f) == nullptr) continue;
    ++sightings_in_graph;
    Eigen::VectorXd e(f.residual_dim());
    f.error(sm.linearization_point(), e);
    const double chi2 = e.dot(f.information() * e);
    CHECK(sm.robust_weight_of(i) == doctest::Approx(dcs(phi_sighting, chi2)).epsilon(1e-12));
    heavier_at_loop_width += dcs(phi_loop, chi2) > 1.2 * dcs(phi_sighting, chi2) ? 1 : 0;  // (16.27 / 13.82)^2 far out
  }
  CHECK(sightings_in_graph == counter(graph_stage_of(*open_auto), "sightings_accepted"));
  MESSAGE(heavier_at_loop_width << " of " << sightings_in_graph << " sightings would weigh more at the loops' width");
  CHECK(heavier_at_loop_width >= wrong);
  // And the wrong sightings still leave the map where the clean run (auto) has it.
  const auto clean_auto = run_with(sightings, 1000, true, std::nullopt);
  const double with_auto = largest_shift(graph_stage_of(*clean_auto), graph_stage_of(*open_auto));
  // For comparison, sightings at the loops' width (the behaviour before they had their own; no loops in this run).
  const auto open_loop_width = run_with(with_wrong, 1000, true, phi_loop),
             clean_loop_width = run_with(sightings, 1000, true, phi_loop);
  MESSAGE("map moved by the wrong sightings past an open gate: "
          << with_auto << " m at the sightings' own width, "
          << largest_shift(graph_stage_of(*clean_loop_width), graph_stage_of(*open_loop_width)) << " m at the loops'");
  CHECK(with_auto < 0.02);
}

TEST_CASE(
    "graph stage: sightings of an unknown body, before the first keyframe, without an id or malformed are counted") {
  const Run run = circle_run(10, 5);
  const Emit ignore = [](Output) {};
  Engine engine(graph_only_config(false));
  GraphStage* graph = &graph_stage_of(engine);
  const auto landmarks = ring_landmarks();
  LandmarkSightings s;
  s.source = "robot";
  s.planar = true;
  s.utime = run.odometry.front().utime - 1;
  s.observations = {sighting_of(run.truth.front().second, landmarks[0], 100)};
  engine.handle(s, ignore);  // the body has sent no odometry yet
  CHECK(counter(*graph, "sightings_unknown_source") == 1);
  for (size_t k = 0; k < 20; ++k) engine.handle(run.odometry[k], ignore);
  engine.handle(s, ignore);  // before the body's first keyframe
  CHECK(counter(*graph, "sightings_before_keyframe") == 1);
  s.source = "nobody";
  s.utime = run.odometry[19].utime;
  engine.handle(s, ignore);
  CHECK(counter(*graph, "sightings_unknown_source") == 2);

  // At the latest odometry time: used at once.  Without an id: counted, not used.  NaN, a non-positive-definite
  // covariance, a 3-D sighting of a planar body: malformed.
  s.source = "robot";
  s.observations = {sighting_of(run.truth[19].second, landmarks[0], 100),
                    sighting_of(run.truth[19].second, landmarks[1], -1)};
  engine.handle(s, ignore);
  CHECK(counter(*graph, "sightings_accepted") == 1);
  CHECK(counter(*graph, "sightings_without_id") == 1);
  CHECK(counter(*graph, "landmarks") == 1);
  s.observations = {sighting_of(run.truth[19].second, landmarks[0], 100)};
  s.observations[0].range = std::nan("");
  engine.handle(s, ignore);
  s.observations = {sighting_of(run.truth[19].second, landmarks[0], 100)};
  s.observations[0].covariance(1, 1) = -1;
  engine.handle(s, ignore);
  s.observations = {sighting_of(run.truth[19].second, landmarks[0], 100)};
  s.planar = false;
  engine.handle(s, ignore);
  CHECK(counter(*graph, "sightings_malformed") == 3);
  CHECK(counter(*graph, "sightings_accepted") == 1);

  // Ahead of the odometry: waits, then is anchored when the odometry passes its time.
  s.planar = true;
  s.utime = run.odometry[30].utime + 30'000;
  s.observations = {sighting_of(circle_truth(3.03), landmarks[0], 100)};
  engine.handle(s, ignore);
  CHECK(counter(*graph, "sightings_accepted") == 1);
  for (size_t k = 20; k < run.odometry.size(); ++k) engine.handle(run.odometry[k], ignore);
  CHECK(counter(*graph, "sightings_accepted") == 2);
  CHECK(counter(*graph, "sightings_rejected") == 0);
  // Older than the odometry kept (history of 100 poses, halved when full): unmatched.
  EngineConfig small = graph_only_config(false);
  small.graph.odometry_history = 10;
  Engine short_memory(small);
  for (size_t k = 0; k < 40; ++k) short_memory.handle(run.odometry[k], ignore);
  s.utime = run.odometry[10].utime + 30'000;
  s.observations = {sighting_of(circle_truth(1.03), landmarks[0], 100)};
  short_memory.handle(s, ignore);
  CHECK(counter(graph_stage_of(short_memory), "sightings_unmatched") == 1);
  // Sightings ahead of the odometry are kept up to max_waiting messages: the oldest beyond that is dropped, counted.
  EngineConfig few = graph_only_config(false);
  few.graph.landmarks.max_waiting = 2;
  Engine waiting(few);
  for (size_t k = 0; k < 10; ++k) waiting.handle(run.odometry[k], ignore);
  for (size_t k = 20; k < 23; ++k) {
    s.utime = run.odometry[k].utime + 30'000;
    s.observations = {sighting_of(circle_truth(static_cast<double>(k) * 0.1 + 0.03), landmarks[0], 100)};
    waiting.handle(s, ignore);
  }
  CHECK(counter(graph_stage_of(waiting), "sightings_dropped") == 1);
  for (size_t k = 10; k < 30; ++k) waiting.handle(run.odometry[k], ignore);
  CHECK(counter(graph_stage_of(waiting), "sightings_accepted") == 2);
}

TEST_CASE("graph stage: a 3-D body maps 3-D landmarks from range, azimuth and elevation") {
  const Run run = spatial_run(circle_run(120, 3), 21);
  const auto sightings = ring_sightings(run, 13, false);
  Engine engine(graph_only_config(false));
  GraphStage* graph = &graph_stage_of(engine);
  feed(engine, run, sightings, [](Output) {});
  CHECK(counter(*graph, "landmarks") == 12);
  CHECK(counter(*graph, "sightings_malformed") == 0);
  CHECK(counter(*graph, "sightings_accepted") > 300);

  const auto [ate, ate_dr] = keyframe_and_dead_reckoning_ate(*graph, run);
  MESSAGE("3-D keyframe ATE " << ate.error.rmse << " m, dead reckoning " << ate_dr.error.rmse << " m");
  CHECK(ate.error.rmse < 0.25 * ate_dr.error.rmse);
  for (const auto& l : graph->landmarks("robot")) {
    const size_t i = static_cast<size_t>(l.id - 100);
    const Eigen::Vector3d want(ring_landmarks()[i].x(), ring_landmarks()[i].y(),
                               i % 3 == 0   ? 1.0
                               : i % 3 == 1 ? -0.5
                                            : 2.0);
    CHECK((ate.rotation * l.position + ate.translation - want).norm() < 0.3);
  }
}

namespace {

GraphConfig keyframe_per_metre_config() { return graph_only_config(false).graph; }

std::vector<int64_t> keyframe_times(const GraphStage& g, const std::string& source = "fast") {
  std::vector<int64_t> out;
  for (const auto& k : g.keyframes(source)) out.push_back(k.utime);
  return out;
}

}  // namespace

TEST_CASE("graph stage: out-of-order and duplicate odometry are counted and dropped") {
  const Emit ignore = [](Output) {};
  GraphConfig cfg = keyframe_per_metre_config();
  cfg.keyframes.k1 = 0.2;
  Run fast = circle_run(3, 7, 1000, "fast");
  std::vector<Odometry> sent = fast.odometry;
  sent.insert(sent.begin() + 501, fast.odometry[500]);   // a duplicate stamp
  sent.insert(sent.begin() + 1002, fast.odometry[999]);  // an old message after a newer one

  GraphStage with_bad(cfg, std::make_shared<GraphCorrections>());
  for (const auto& o : sent) with_bad.handle(o, ignore);
  CHECK(counter(with_bad, "odometry_out_of_order") == 2);
  GraphStage clean(cfg, std::make_shared<GraphCorrections>());
  for (const auto& o : fast.odometry) clean.handle(o, ignore);
  CHECK(counter(clean, "odometry_out_of_order") == 0);
  CHECK(keyframe_times(with_bad).size() > 10);
  CHECK(keyframe_times(with_bad) == keyframe_times(clean));
}

TEST_CASE(
    "graph stage: after a real jump keyframing re-anchors and loops pull the new segment in, a spike is rejected") {
  // 60 s on the circle at 10 Hz; the odometry stops at 20 s and resumes at 30 s (the robot went on 10 m meanwhile:
  // a 9.6 m chord, > k2 = 5) with a wrong guess of that motion (0.5 m and 0.1 rad off, as a visual odometry that
  // re-initialized).  The matcher answers loop proposals from the truth.
  Run run = circle_run(60, 5, 10, "fast");
  const int64_t t0 = run.odometry.front().utime;
  const SE3 reinit_error(SO3::exp(Eigen::Vector3d(0, 0, 0.1)), Eigen::Vector3d(0.5, -0.3, 0));
  std::vector<Odometry> kept;
  for (Odometry o : run.odometry) {
    if (o.utime >= t0 + 20'000'000 && o.utime < t0 + 30'000'000) continue;
    if (o.utime >= t0 + 30'000'000) o.pose = to_pose(reinit_error * to_se3(o.pose));
    kept.push_back(o);
  }
  run.odometry = kept;
  std::map<std::string, tools::MatcherTruth> truth;
  truth["fast"] = {tools::InterpolatedTrajectory(run.truth), true};
  EngineConfig cfg = graph_only_config(true);
  cfg.graph.proposals.n1 = 2;
  REQUIRE(cfg.graph.keyframes.reanchor_after == 10);  // the default
  Engine engine(cfg);
  GraphStage& graph = graph_stage_of(engine);
  tools::SimulatedMatcher matcher(truth, tools::SimulatedMatcherOptions{});
  std::vector<MatchRequest> requests;
  const Emit emit = [&](Output out) {
    if (auto* r = std::get_if<MatchRequest>(&out)) requests.push_back(*r);
  };
  for (const auto& o : run.odometry) {
    engine.handle(o, emit);
    for (const MatchRequest& r : std::exchange(requests, {}))
      if (auto answer = matcher.answer(r)) engine.handle(*answer, emit);
  }
  CHECK(counter(graph, "keyframes_reanchored") == 1);
  CHECK(counter(graph, "keyframes_rejected") == 9);  // the nine poses before the tenth re-anchored
  const auto kfs = graph.keyframes("fast");
  std::map<int64_t, SE3> truth_at(run.truth.begin(), run.truth.end()), odo;
  for (const auto& o : run.odometry) odo[o.utime] = to_se3(o.pose);
  // The re-anchored keyframe is the tenth message after the gap; keyframing goes on after it.
  const auto first_after =
      std::find_if(kfs.begin(), kfs.end(), [&](const Keyframe& k) { return k.utime >= t0 + 30'000'000; });
  REQUIRE(first_after != kfs.end());
  CHECK(first_after->utime == t0 + 30'900'000);
  CHECK(std::distance(first_after, kfs.end()) >= 25);
  // After the jump: the odometry is off by the re-initialization, the keyframes are back on the truth (the map frame
  // is the odometry's at the first keyframe, which is the truth there).
  double odo_err = 0, kf_err = 0;
  int n = 0;
  for (auto k = first_after; k != kfs.end(); ++k, ++n) {
    odo_err += (odo.at(k->utime).translation() - truth_at.at(k->utime).translation()).squaredNorm();
    kf_err += (to_se3(k->pose).translation() - truth_at.at(k->utime).translation()).squaredNorm();
  }
  odo_err = std::sqrt(odo_err / n), kf_err = std::sqrt(kf_err / n);
  MESSAGE("after the jump: odometry RMS error " << odo_err << " m, keyframes " << kf_err << " m");
  CHECK(odo_err > 0.5);
  CHECK(kf_err < 0.2 * odo_err);

  // Without loops: one spurious spike (20 m off for one message) is rejected and changes no keyframe.
  Run spiked = run;
  Odometry& spike = spiked.odometry[100];
  spike.pose.position.x() += 20;
  GraphStage plain(graph_only_config(false).graph, std::make_shared<GraphCorrections>());
  GraphStage with_spike(graph_only_config(false).graph, std::make_shared<GraphCorrections>());
  const Emit ignore = [](Output) {};
  for (size_t k = 0; k < run.odometry.size(); ++k) {
    plain.handle(run.odometry[k], ignore);
    with_spike.handle(spiked.odometry[k], ignore);
  }
  CHECK(counter(with_spike, "keyframes_rejected") == counter(plain, "keyframes_rejected") + 1);
  CHECK(counter(with_spike, "keyframes_reanchored") == 1);
  const auto kp = plain.keyframes("fast"), ks = with_spike.keyframes("fast");
  REQUIRE(kp.size() == ks.size());
  for (size_t k = 0; k < kp.size(); ++k) CHECK(kp[k].utime == ks[k].utime);
}

namespace {

// A planar body ("fast") along x through `xs` (m) at 10 Hz, increment covariances 1e-4 on x, y and yaw; the increments
// into the messages listed in `x_variance` have that x variance instead (negative: an indefinite one, floored).
std::vector<Odometry> straight_run(const std::vector<double>& xs, const std::map<size_t, double>& x_variance) {
  std::vector<Odometry> out;
  for (size_t k = 0; k < xs.size(); ++k) {
    Odometry o;
    o.utime = 1'000'000 + static_cast<int64_t>(k) * 100'000;
    o.source = "fast";
    o.planar = true;
    o.pose.position.x() = xs[k];
    Matrix6 inc = Matrix6::Zero();
    inc(0, 0) = inc(1, 1) = inc(5, 5) = 1e-4;
    if (auto it = x_variance.find(k); it != x_variance.end()) inc(0, 0) = it->second;
    o.increment_covariance = inc;
    out.push_back(o);
  }
  return out;
}

}  // namespace

TEST_CASE("graph stage: an indefinite stated increment is floored (estimators/spd_matrix.hpp), its keyframe enters") {
  // Every estimator floors the eigenvalues of an increment covariance at min_increment_variance, so an indefinite
  // one a caller states (the bus's intake refuses it) no longer makes an edge covariance indefinite: no keyframe is
  // dropped for its edge, none is re-anchored.
  const Emit ignore = [](Output) {};
  GraphConfig cfg = keyframe_per_metre_config();
  cfg.keyframes.k1 = 0.3;  // k2 = 5: the default
  REQUIRE(cfg.keyframes.k2 == 5.0);
  struct Scenario {
    const char* name;
    std::vector<Odometry> run;
    std::vector<size_t> keyframes;  // the messages that become keyframes
  };
  std::vector<Scenario> scenarios;
  {
    std::vector<double> xs;  // 0.2 m per message: a keyframe every second one
    for (int k = 0; k < 8; ++k) xs.push_back(0.2 * k);
    scenarios.push_back({"one step", straight_run(xs, {{2, -0.01}, {3, 0.02}}), {0, 2, 4, 6}});
  }
  {
    std::vector<double> xs = {0};  // 4.9 m out (within k2), then 0.4 m steps: every message a keyframe
    for (int k = 0; k < 14; ++k) xs.push_back(4.9 + 0.4 * k);
    std::vector<size_t> all;
    for (size_t k = 0; k < xs.size(); ++k) all.push_back(k);
    scenarios.push_back({"near k2", straight_run(xs, {{1, -0.01}, {2, 0.02}}), all});
  }
  for (const Scenario& sc : scenarios) {
    const std::string name = sc.name;
    CAPTURE(name);
    GraphStage slow(cfg, std::make_shared<GraphCorrections>());
    for (const auto& o : sc.run) slow.handle(o, ignore);
    std::vector<int64_t> want;
    for (size_t k : sc.keyframes) want.push_back(sc.run[k].utime);
    CHECK(keyframe_times(slow) == want);
    CHECK(counter(slow, "odometry_edges_rejected") == 0);
    CHECK(counter(slow, "keyframes_rejected") == 0);
    CHECK(counter(slow, "keyframes_reanchored") == 0);
  }
}
