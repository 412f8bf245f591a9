// The filter stage on a simulated run: one EKF pose per odometry message, and a far smaller error against the
// ground truth than dead reckoning (landmark sightings correct the drift).
#include "daemon/engine/filter_stage.hpp"
#include "daemon/engine/graph_stage.hpp"
#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/lcm_log.hpp"
#include "replay/replay_driver.hpp"
#include "sim/simulator.hpp"
#include "eval/trajectory_eval.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <random>

using namespace sextant;

TEST_CASE("EKF-SLAM beats dead reckoning on a simulated planar run") {
  const auto log =
      (std::filesystem::temp_directory_path() / ("sextant_filter_" + std::to_string(::getpid()) + ".lcm")).string();
  tools::SimulationOptions o;
  o.duration_s = 60;
  o.seed = 4;
  {
    runtime::LogWriter w(log);
    tools::simulate(o, w);
  }
  config::DaemonConfig cfg;
  const auto r = tools::replay_log(log, cfg);
  REQUIRE(r.fused_poses.contains("ekf"));
  const auto& ekf = r.fused_poses.at("ekf");
  const auto& dr = r.fused_poses.at("dead_reckoning");
  CHECK(ekf.size() == dr.size());
  std::vector<tools::StampedPose> truth, e, d;
  for (const auto& t : r.truth_poses) truth.push_back({t.utime * 1e-6, t.pose});
  for (const auto& p : ekf) e.push_back({p.utime * 1e-6, p.pose});
  for (const auto& p : dr) d.push_back({p.utime * 1e-6, p.pose});
  const double ate_ekf = tools::absolute_trajectory_error(truth, e).error.rmse;
  const double ate_dr = tools::absolute_trajectory_error(truth, d).error.rmse;
  MESSAGE("ATE ekf " << ate_ekf << " m, dead reckoning " << ate_dr << " m");
  CHECK(ate_ekf < 0.5 * ate_dr);
  CHECK(ate_ekf < 0.1);
  // Published covariances are positive on x, y, yaw.
  CHECK(ekf.back().covariance(0, 0) > 0);
  CHECK(ekf.back().covariance(5, 5) > 0);
  std::remove(log.c_str());
}

TEST_CASE("landmarks without ids: JCBB association and tentative landmarks recover the map") {
  const auto log =
      (std::filesystem::temp_directory_path() / ("sextant_filter_unk_" + std::to_string(::getpid()) + ".lcm")).string();
  tools::SimulationOptions o;
  o.duration_s = 60;
  o.seed = 6;
  o.unknown_ids = true;
  {
    runtime::LogWriter w(log);
    tools::simulate(o, w);
  }
  config::DaemonConfig cfg;
  const auto r = tools::replay_log(log, cfg);
  std::map<std::string, int64_t> c;
  for (const auto& s : r.stages)
    if (s.name == "filter")
      for (const auto& [k, v] : s.counters) c[k] = v;
  int64_t seen_landmarks = 0;
  for (const auto& p : r.truth_points) seen_landmarks += p.kind == "landmark";
  MESSAGE("associated " << c["associated"] << ", landmarks created " << c["new_landmarks"] << " of " << seen_landmarks);
  CHECK(c["associated"] > 1000);
  CHECK(c["new_landmarks"] <= seen_landmarks);      // no duplicates or spurious permanent landmarks
  CHECK(c["new_landmarks"] >= seen_landmarks / 2);  // most of the landmarks the robot passes are mapped
  std::vector<tools::StampedPose> truth, e, d;
  for (const auto& t : r.truth_poses) truth.push_back({t.utime * 1e-6, t.pose});
  for (const auto& p : r.fused_poses.at("ekf")) e.push_back({p.utime * 1e-6, p.pose});
  for (const auto& p : r.fused_poses.at("dead_reckoning")) d.push_back({p.utime * 1e-6, p.pose});
  CHECK(tools::absolute_trajectory_error(truth, e).error.rmse <
        0.5 * tools::absolute_trajectory_error(truth, d).error.rmse);
  std::remove(log.c_str());
}

namespace {

// The odometry and landmark events of a simulated planar run, in log order.
std::vector<engine::Event> simulated_events(const tools::SimulationOptions& o) {
  const auto log =
      (std::filesystem::temp_directory_path() / ("sextant_filter_ev_" + std::to_string(::getpid()) + ".lcm")).string();
  {
    runtime::LogWriter w(log);
    tools::simulate(o, w);
  }
  std::vector<engine::Event> out;
  for (const auto& r : runtime::LogReader::read_all(log)) {
    const bool odo = r.channel == "ODOMETRY", lm = r.channel == "LANDMARKS";
    if (!odo && !lm) continue;
    auto d = runtime::decode_event(odo ? runtime::InputKind::kOdometry : runtime::InputKind::kLandmarks, r.data.data(),
                                   r.data.size());
    if (auto* e = std::get_if<engine::Event>(&d)) out.push_back(*e);
  }
  std::remove(log.c_str());
  return out;
}

std::map<std::string, int64_t> counters_of(const engine::Stage& s) {
  std::map<std::string, int64_t> c;
  for (const auto& [k, v] : s.counters()) c[k] = v;
  return c;
}

}  // namespace

TEST_CASE("filter stage: late odometry and sightings inside the window give the in-order state") {
  tools::SimulationOptions o;
  o.duration_s = 20;
  o.seed = 8;
  const auto events = simulated_events(o);
  engine::FilterConfig cfg;
  cfg.history_s = 0.5;
  engine::FilterStage in_order(cfg), late(cfg);
  std::vector<engine::FusedPose> poses_in_order, poses_late;
  for (const auto& e : events)
    in_order.handle(e, [&](engine::Output out) { poses_in_order.push_back(std::get<engine::FusedPose>(out)); });
  // Arrival: sightings up to 0.4 s late, odometry up to 0.1 s late (so odometry messages overtake each other too).
  std::mt19937 rng(2);
  std::vector<std::pair<int64_t, size_t>> arrival;
  for (size_t i = 0; i < events.size(); ++i) {
    const bool odo = std::holds_alternative<engine::Odometry>(events[i]);
    arrival.push_back({engine::event_utime(events[i]) +
                           static_cast<int64_t>(std::uniform_real_distribution<double>(0, odo ? 1e5 : 4e5)(rng)),
                       i});
  }
  std::stable_sort(arrival.begin(), arrival.end());
  for (const auto& [t, i] : arrival)
    late.handle(events[i], [&](engine::Output out) { poses_late.push_back(std::get<engine::FusedPose>(out)); });
  const auto* a = in_order.ekf(o.source);
  const auto* b = late.ekf(o.source);
  REQUIRE(a != nullptr);
  REQUIRE(b != nullptr);
  REQUIRE(a->state().size() == b->state().size());
  CHECK(a->landmark_count() > 10);
  CHECK((a->state() - b->state()).cwiseAbs().maxCoeff() <= 1e-12);
  CHECK((a->covariance() - b->covariance()).cwiseAbs().maxCoeff() <= 1e-12);
  const auto ca = counters_of(in_order), cb = counters_of(late);
  CHECK(cb.at("late_reapplied") > 100);
  CHECK(cb.at("too_late") == 0);
  for (const char* k : {"predictions", "updates", "new_landmarks", "gated"}) CHECK(ca.at(k) == cb.at(k));
  // Published stamps strictly increase; late odometry is not published, so fewer poses come out.
  CHECK(poses_in_order.size() ==
        events.size() - static_cast<size_t>(std::count_if(events.begin(), events.end(), [](const engine::Event& e) {
          return std::holds_alternative<engine::LandmarkSightings>(e);
        })));
  CHECK(poses_late.size() < poses_in_order.size());
  for (size_t i = 1; i < poses_late.size(); ++i) CHECK(poses_late[i].utime > poses_late[i - 1].utime);
}

TEST_CASE("filter stage: too late, duplicate and backwards stamps are counted and dropped") {
  tools::SimulationOptions o;
  o.duration_s = 4;
  o.seed = 9;
  const auto events = simulated_events(o);
  engine::FilterConfig cfg;
  cfg.history_s = 0.2;
  engine::FilterStage stage(cfg), reference(cfg);
  int emitted = 0;
  const auto count = [&](engine::Output) { ++emitted; };
  const engine::Event* held = nullptr;
  for (const auto& e : events) {
    if (held == nullptr && std::holds_alternative<engine::LandmarkSightings>(e) &&
        engine::event_utime(e) > o.start_utime + 1'000'000) {
      held = &e;
      continue;
    }
    stage.handle(e, count);
    reference.handle(e, [](engine::Output) {});
  }
  REQUIRE(held != nullptr);
  const int before = emitted;
  stage.handle(*held, count);  // about 3 s late, window 0.2 s
  const auto& last_odo = *std::find_if(events.rbegin(), events.rend(), [](const engine::Event& e) {
    return std::holds_alternative<engine::Odometry>(e);
  });
  stage.handle(last_odo, count);  // the same odometry message again: duplicate stamp
  auto backwards = std::get<engine::Odometry>(last_odo);
  backwards.utime -= 10'000'000;  // far behind: too late
  stage.handle(backwards, count);
  CHECK(emitted == before);
  const auto c = counters_of(stage);
  CHECK(c.at("too_late") == 2);
  CHECK(c.at("duplicate_stamps") == 1);
  CHECK((stage.ekf(o.source)->state() - reference.ekf(o.source)->state()).cwiseAbs().maxCoeff() == 0.0);
}

TEST_CASE("filter stage: a second odometry source of the same body is fused, timed out and reported") {
  tools::SimulationOptions o;
  o.duration_s = 10;
  o.seed = 10;
  const auto events = simulated_events(o);
  engine::FilterConfig one, two;
  two.sources["vo"] = {};
  two.sources["vo"].body = o.source;  // robot1's own odometry predicts, "vo" is fused differentially
  two.sources["vo"].gate = 16.27;     // chi-square 3 dof, 99.9 %
  two.sources["vo"].timeout_s = 0.2;
  engine::FilterStage single(one), fused(two);
  std::vector<engine::FusedPose> out_single, out_fused;
  int64_t vo_messages = 0;
  for (const auto& e : events) {
    single.handle(e, [&](engine::Output x) { out_single.push_back(std::get<engine::FusedPose>(x)); });
    fused.handle(e, [&](engine::Output x) { out_fused.push_back(std::get<engine::FusedPose>(x)); });
    // "vo": the same odometry under another name and in another frame, silent after 5 s.
    if (const auto* od = std::get_if<engine::Odometry>(&e); od != nullptr && od->utime < o.start_utime + 5'000'000) {
      auto vo = *od;
      vo.source = "vo";
      vo.pose.position += Eigen::Vector3d(3, -2, 0);
      fused.handle(vo, [&](engine::Output x) { out_fused.push_back(std::get<engine::FusedPose>(x)); });
      ++vo_messages;
    }
  }
  CHECK(fused.body_of("vo") == o.source);
  // One pose per prediction of the body, published under the body's name.
  CHECK(out_fused.size() == out_single.size());
  for (const auto& p : out_fused) CHECK(p.source == o.source);
  const auto c = counters_of(fused);
  CHECK(c.at("source.vo.fused") == vo_messages - 1);  // the first message anchors
  CHECK(c.at("source.vo.gated") == 0);
  CHECK(c.at("source.vo.timeouts") == 1);
  CHECK(c.at("source.vo.silent") == 1);
  // While vo was fused, the pose covariance was smaller than with the wheel alone.
  const size_t mid = out_single.size() / 4;
  CHECK(out_fused[mid].covariance(0, 0) < out_single[mid].covariance(0, 0));
  CHECK(out_fused[mid].covariance(5, 5) < out_single[mid].covariance(5, 5));
}

TEST_CASE("filter stage: sightings after the newest prediction wait for the next one, at most 64 batches") {
  tools::SimulationOptions o;
  o.duration_s = 1;
  o.seed = 12;
  const auto events = simulated_events(o);
  engine::FilterStage stage(engine::FilterConfig{});
  engine::LandmarkSightings batch;
  int64_t last = 0;
  for (const auto& e : events) {
    stage.handle(e, [](engine::Output) {});
    if (const auto* s = std::get_if<engine::LandmarkSightings>(&e); s != nullptr && !s->observations.empty())
      batch = *s;
    last = std::max(last, engine::event_utime(e));
  }
  REQUIRE(!batch.observations.empty());
  const auto before = counters_of(stage);
  // The odometry stops; 70 more batches arrive after the last prediction.
  for (int k = 1; k <= 70; ++k) {
    batch.utime = last + 1000 * k;
    stage.handle(batch, [](engine::Output) {});
  }
  const auto c = counters_of(stage);
  CHECK(c.at("sightings_without_prediction") == 6);
  CHECK(c.at("updates") == before.at("updates"));  // none applied yet: they wait for a prediction
}

TEST_CASE("filter stage: a 3-D body gets the 3-D EKF-SLAM, better than dead reckoning") {
  const auto log =
      (std::filesystem::temp_directory_path() / ("sextant_filter_3d_" + std::to_string(::getpid()) + ".lcm")).string();
  tools::SimulationOptions o;
  o.scenario = tools::Scenario::kSpatial;
  o.duration_s = 60;
  o.seed = 5;
  {
    runtime::LogWriter w(log);
    tools::simulate(o, w);
  }
  config::DaemonConfig cfg;
  const auto r = tools::replay_log(log, cfg);
  std::remove(log.c_str());
  REQUIRE(r.fused_poses.contains("ekf"));
  const auto& ekf = r.fused_poses.at("ekf");
  CHECK(ekf.size() == r.fused_poses.at("dead_reckoning").size());
  CHECK_FALSE(ekf.back().planar);
  std::vector<tools::StampedPose> truth, e, d;
  for (const auto& t : r.truth_poses) truth.push_back({t.utime * 1e-6, t.pose});
  for (const auto& p : ekf) e.push_back({p.utime * 1e-6, p.pose});
  for (const auto& p : r.fused_poses.at("dead_reckoning")) d.push_back({p.utime * 1e-6, p.pose});
  const double ate_ekf = tools::absolute_trajectory_error(truth, e).error.rmse;
  const double ate_dr = tools::absolute_trajectory_error(truth, d).error.rmse;
  MESSAGE("3-D: ATE ekf " << ate_ekf << " m, dead reckoning " << ate_dr << " m");
  // Better than dead reckoning, by less than in the plane: 3-D SLAM without a map over 60 s (its consistency is
  // checked in test_filter_consistency).
  CHECK(ate_ekf < 0.9 * ate_dr);
  std::map<std::string, int64_t> c;
  for (const auto& s : r.stages)
    if (s.name == "filter")
      for (const auto& [k, v] : s.counters) c[k] = v;
  MESSAGE("updates " << c["updates"] << " gated " << c["gated"] << " new " << c["new_landmarks"] << " rejected "
                     << c["rejected"] << " predictions " << c["predictions"]);
  CHECK(c["updates"] > 1000);
  CHECK(c["new_landmarks"] <= o.landmarks);
  CHECK(c["mixed_dimensions"] == 0);
  // The full 6x6 covariance is published: z, roll and pitch too.
  for (int i = 0; i < 6; ++i) CHECK(ekf.back().covariance(i, i) > 0);
}

TEST_CASE("filter stage: two replays of a log give identical EKF poses") {
  const auto log =
      (std::filesystem::temp_directory_path() / ("sextant_filter_det_" + std::to_string(::getpid()) + ".lcm")).string();
  tools::SimulationOptions o;
  o.duration_s = 12;
  o.seed = 3;
  {
    runtime::LogWriter w(log);
    tools::simulate(o, w);
  }
  config::DaemonConfig cfg;
  const auto a = tools::replay_log(log, cfg), b = tools::replay_log(log, cfg);
  std::remove(log.c_str());
  const auto& pa = a.fused_poses.at("ekf");
  const auto& pb = b.fused_poses.at("ekf");
  REQUIRE(pa.size() == pb.size());
  bool same = true;
  for (size_t i = 0; i < pa.size(); ++i)
    same = same && pa[i].utime == pb[i].utime && pa[i].pose.position == pb[i].pose.position &&
           pa[i].pose.orientation.coeffs() == pb[i].pose.orientation.coeffs() && pa[i].covariance == pb[i].covariance;
  CHECK(same);
}

TEST_CASE("filter stage: recover after a failed event forgets that body only, which restarts from its next odometry") {
  tools::SimulationOptions o;
  o.duration_s = 2;
  o.seed = 9;
  const auto events = simulated_events(o);
  engine::FilterStage stage(engine::FilterConfig{});
  const engine::Event* first_odometry = nullptr;
  for (const auto& e : events) {
    stage.handle(e, [](engine::Output) {});
    if (first_odometry == nullptr && std::holds_alternative<engine::Odometry>(e)) first_odometry = &e;
  }
  REQUIRE(first_odometry != nullptr);
  REQUIRE(stage.ekf(o.source) != nullptr);
  engine::Odometry other = std::get<engine::Odometry>(*first_odometry);
  other.source = "other";
  stage.handle(other, [](engine::Output) {});
  REQUIRE(stage.ekf("other") != nullptr);
  stage.recover(*first_odometry);  // as the stage runner does after handle threw on it
  CHECK(stage.ekf(o.source) == nullptr);
  CHECK(stage.ekf("other") != nullptr);
  // The body's next odometry message starts a fresh filter and publishes again.
  auto next = std::get<engine::Odometry>(*first_odometry);
  next.utime = engine::event_utime(events.back()) + 1'000'000;
  int published = 0;
  stage.handle(next, [&](engine::Output) { ++published; });
  next.utime += 20'000;
  stage.handle(next, [&](engine::Output) { ++published; });
  REQUIRE(stage.ekf(o.source) != nullptr);
  CHECK(published >= 1);
}

TEST_CASE("graph stage: recover refactorizes from the graph and keeps every keyframe, and the stage goes on") {
  tools::SimulationOptions o;
  o.duration_s = 20;
  o.seed = 3;
  const auto events = simulated_events(o);
  engine::GraphConfig config;
  config.solve_period_s = 0;  // every input solved: the keyframes before the recovery are the incremental solution
  engine::GraphStage stage(config, std::make_shared<engine::GraphCorrections>());
  engine::GraphStage reference(config, std::make_shared<engine::GraphCorrections>());
  const size_t half = events.size() / 2;
  for (size_t i = 0; i < half; ++i) {
    stage.handle(events[i], [](engine::Output) {});
    reference.handle(events[i], [](engine::Output) {});
  }
  const auto before = stage.keyframes(o.source);
  REQUIRE(before.size() > 3);
  CHECK_NOTHROW(stage.recover(events[half - 1]));  // as the stage runner does after handle threw
  const auto after = stage.keyframes(o.source);
  REQUIRE(after.size() == before.size());
  // A rebuild re-solves from the graph (Gauss-Newton from the current estimate): the keyframes move by at most a
  // fraction of a millimetre.
  for (size_t k = 0; k < after.size(); ++k) CHECK((after[k].pose.position - before[k].pose.position).norm() < 1e-3);
  for (size_t i = half; i < events.size(); ++i) {
    stage.handle(events[i], [](engine::Output) {});
    reference.handle(events[i], [](engine::Output) {});
  }
  const auto end = stage.keyframes(o.source), ref = reference.keyframes(o.source);
  REQUIRE(end.size() == ref.size());
  CHECK((end.back().pose.position - ref.back().pose.position).norm() < 1e-3);
}
