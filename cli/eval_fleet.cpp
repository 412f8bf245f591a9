// sextant eval fleet --out-log OUT.lcm [--out-log ...] (--gt-prefix PREFIX | --gt-log IN.lcm) [--estimator graph] [--spatial]
//                    [--max-difference S] [--json]
//
// A fleet's final map from a replay's output log against the ground truth under one alignment (eval/fleet_eval.hpp):
// per robot the ATE of its final keyframes in the fleet frame and under its own alignment, the ATE of its online
// fused pose (FUSED_POSE of --estimator, aligned per robot as `sextant eval` does), and the landmarks' RMSE.
//
// --json keys:
//   alignment            "SE(2)" or "SE(3)"
//   alignment_yaw        rad, rotation about z of the fleet's alignment (estimate -> ground truth)
//   alignment_translation [x, y, z], metres
//   points               keyframes and landmarks in the alignment
//   frames               distinct map frames the bodies' last TRAJECTORY messages name (1 once the fleet is joined)
//   landmark_frame       the map frame whose LANDMARK_MAP was evaluated (the frame most bodies are in)
//   landmarks_estimated, landmarks_matched, landmark_rmse, landmark_max   (metres; rmse null without a match)
//   fleet_ate_rmse_max   the largest fleet_ate_rmse over the robots
//   robots               {BODY: {frame, keyframes, matched, fleet_ate_rmse, fleet_ate_max, own_ate_rmse,
//                                online_poses, online_matched, online_ate_rmse, online_joined_poses,
//                                online_joined_ate_rmse}}  (metres; online_joined_*: over the fused poses published
//                                in the map frame the body ended in; an ATE is null with fewer than 2 poses matched)
// Registered as "eval fleet": the registry adds commands in name order, so `eval` exists when this one is added.
#include "cli/command.hpp"
#include "eval/fleet_eval.hpp"
#include "eval/fleet_log.hpp"
#include "report/json_writer.hpp"

#include <cmath>
#include <cstdio>
#include <limits>
#include <set>
#include <stdexcept>

namespace {

using namespace sextant::tools;

struct Options {
  std::vector<std::string> out_logs;
  std::string gt_prefix, gt_log, estimator = "graph";
  bool spatial = false, json = false;
  double max_difference = 0.02;
};

struct OnlineError {
  size_t poses = 0, matched = 0;
  double rmse = std::numeric_limits<double>::quiet_NaN();
  // The same over the fused poses published in the map frame the body ended in (after it joined the fleet's).
  size_t joined_poses = 0;
  double joined_rmse = std::numeric_limits<double>::quiet_NaN();
};

// ATE RMSE of `poses` against `gt` (sextant eval's alignment), NaN when fewer than 2 match.
double ate_rmse(const std::vector<StampedPose>& gt, const std::vector<StampedPose>& poses, double window,
                size_t* matched = nullptr) {
  try {
    const AteResult ate = absolute_trajectory_error(gt, poses, false, window);
    if (matched) *matched = ate.matched;
    return ate.error.rmse;
  } catch (const std::invalid_argument&) {
    return std::numeric_limits<double>::quiet_NaN();
  }
}

// The map frame most bodies are in (the first by name among equals); empty when no body names one.
std::string majority_frame(const std::map<std::string, std::string>& frames) {
  std::map<std::string, int> count;
  for (const auto& [body, frame] : frames) ++count[frame];
  std::string best;
  int most = 0;
  for (const auto& [frame, n] : count)
    if (n > most) best = frame, most = n;
  return best;
}

std::map<std::string, OnlineError> online_errors(const FleetOutput& out, const FleetTruth& truth, double window) {
  std::map<std::string, OnlineError> e;
  for (const auto& [body, poses] : out.fused) {
    OnlineError& o = e[body];
    o.poses = poses.size();
    const auto gt = truth.robots.find(body);
    if (gt == truth.robots.end()) continue;
    o.rmse = ate_rmse(gt->second, poses, window, &o.matched);
    const auto final_frame = out.frames.find(body);
    if (final_frame == out.frames.end()) continue;
    std::vector<StampedPose> joined;
    const auto& frames = out.fused_frames.at(body);
    for (size_t k = 0; k < poses.size(); ++k)
      if (frames[k] == final_frame->second) joined.push_back(poses[k]);
    o.joined_poses = joined.size();
    o.joined_rmse = ate_rmse(gt->second, joined, window);
  }
  return e;
}

void print_json(const Options& o, const FleetOutput& out, const FleetEvaluation& e,
                const std::map<std::string, OnlineError>& online, const std::string& landmark_frame) {
  JsonWriter j;
  const auto& R = e.alignment.rotation;
  j.begin_object().field("alignment", o.spatial ? "SE(3)" : "SE(2)");
  j.field("alignment_yaw", std::atan2(R(1, 0), R(0, 0)));
  j.key("alignment_translation")
      .value(std::vector<double>(e.alignment.translation.data(), e.alignment.translation.data() + 3));
  size_t points = e.landmarks.count;
  double worst = 0;
  for (const auto& [body, r] : e.robots) points += r.matched, worst = std::max(worst, r.fleet.rmse);
  std::set<std::string> frames;
  for (const auto& [body, frame] : out.frames) frames.insert(frame);
  j.field("points", points).field("frames", frames.size());
  j.field("landmark_frame", landmark_frame).field("landmarks_estimated", e.landmarks_estimated);
  j.field("landmarks_matched", e.landmarks.count);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  j.field("landmark_rmse", e.landmarks.count ? e.landmarks.rmse : nan);
  j.field("landmark_max", e.landmarks.count ? e.landmarks.max : nan).field("fleet_ate_rmse_max", worst);
  j.key("robots").begin_object();
  for (const auto& [body, r] : e.robots) {
    const auto f = out.frames.find(body);
    const auto on = online.find(body);
    const OnlineError oe = on == online.end() ? OnlineError{} : on->second;
    j.key(body).begin_object().field("frame", f == out.frames.end() ? "" : f->second);
    j.field("keyframes", r.keyframes).field("matched", r.matched).field("fleet_ate_rmse", r.fleet.rmse);
    j.field("fleet_ate_max", r.fleet.max).field("own_ate_rmse", r.own.rmse).field("online_poses", oe.poses);
    j.field("online_matched", oe.matched).field("online_ate_rmse", oe.rmse);
    j.field("online_joined_poses", oe.joined_poses).field("online_joined_ate_rmse", oe.joined_rmse).end_object();
  }
  j.end_object().end_object();
  std::puts(j.str().c_str());
}

void print_text(const FleetOutput& out, const FleetEvaluation& e, const std::map<std::string, OnlineError>& online) {
  std::printf("%-10s %-10s %9s %8s %15s %13s %16s %16s\n", "body", "frame", "keyframes", "matched", "fleet ATE [m]",
              "own ATE [m]", "online ATE [m]", "since joined [m]");
  for (const auto& [body, r] : e.robots) {
    const auto f = out.frames.find(body);
    const auto on = online.find(body);
    const OnlineError oe = on == online.end() ? OnlineError{} : on->second;
    std::printf("%-10s %-10s %9zu %8zu %15.4f %13.4f %16.4f %16.4f\n", body.c_str(),
                f == out.frames.end() ? "" : f->second.c_str(), r.keyframes, r.matched, r.fleet.rmse, r.own.rmse,
                oe.rmse, oe.joined_rmse);
  }
  std::printf("landmarks: %zu of %zu with ground truth, RMSE %.4f m, max %.4f m (fleet alignment)\n", e.landmarks.count,
              e.landmarks_estimated, e.landmarks.rmse, e.landmarks.max);
}

void run(const Options& o) {
  FleetOutput out;
  FleetTruth truth;
  try {
    for (const auto& path : o.out_logs) merge_into(out, read_fleet_output(path, o.estimator));
    if (!o.gt_log.empty()) {
      truth = read_truth_log(o.gt_log);
    } else {
      std::vector<std::string> bodies;
      for (const auto* m : {&out.keyframes, &out.fused})
        for (const auto& [body, poses] : *m) bodies.push_back(body);
      truth = read_truth_files(o.gt_prefix, bodies);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "sextant eval fleet: %s\n", e.what());
    throw CLI::RuntimeError(2);
  }
  const std::string frame = majority_frame(out.frames);
  const auto map = out.maps.count(frame) ? out.maps.at(frame) : LandmarkPositions{};
  FleetEvaluation e;
  try {
    e = evaluate_fleet(out.keyframes, map, truth.robots, truth.landmarks, {!o.spatial, o.max_difference});
  } catch (const std::exception& ex) {
    std::fprintf(stderr, "sextant eval fleet: %s\n", ex.what());
    throw CLI::RuntimeError(1);
  }
  const auto online = online_errors(out, truth, o.max_difference);
  if (o.json)
    print_json(o, out, e, online, frame);
  else
    print_text(out, e, online);
}

sextant::cli::RegisterCommand reg{
    "eval fleet", [](CLI::App& app) {
      auto* eval = app.get_subcommand("eval");
      auto* cmd = eval->add_subcommand(
          "fleet",
          "a fleet's final keyframes and landmarks (a replay's --out-log) against the ground truth under "
          "one alignment for the whole fleet, and each robot's online fused-pose ATE");
      auto o = std::make_shared<Options>();
      cmd->add_option("--out-log", o->out_logs,
                      "the replay's output log (TRAJECTORY, LANDMARK_MAP, FUSED_POSE*); several: their bodies together "
                      "(e.g. single-robot replays under one alignment)")
          ->required()
          ->check(CLI::ExistingFile);
      auto* prefix = cmd->add_option("--gt-prefix", o->gt_prefix,
                                     "ground truth files PREFIX BODY.txt (TUM) and PREFIX landmarks.txt (id x y [z])");
      auto* log = cmd->add_option("--gt-log", o->gt_log, "ground truth from this log's GROUND_TRUTH (the input log)")
                      ->check(CLI::ExistingFile);
      prefix->excludes(log);
      cmd->add_option("--estimator", o->estimator, "whose FUSED_POSE is the online estimate (default graph)");
      cmd->add_flag("--spatial", o->spatial, "SE(3) alignment (default SE(2), a planar fleet)");
      cmd->add_option("--max-difference", o->max_difference, "association window, seconds")->check(CLI::PositiveNumber);
      cmd->add_flag("--json", o->json, "print JSON (keys in cli/eval_fleet.cpp and docs)");
      cmd->callback([o, prefix, log] {
        if (prefix->count() == 0 && log->count() == 0) {
          std::fprintf(stderr, "sextant eval fleet: give --gt-prefix or --gt-log\n");
          throw CLI::RuntimeError(2);
        }
        run(*o);
      });
    }};

}  // namespace
