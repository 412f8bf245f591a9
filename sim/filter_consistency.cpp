#include "sim/filter_consistency.hpp"

#include "assoc/chi_square.hpp"
#include "daemon/engine/filter_stage.hpp"
#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/lcm_log.hpp"
#include "estimators/lie/planar_axes.hpp"

#include <sextant/truth_t.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <stdexcept>
#include <unistd.h>

namespace sextant::tools {
namespace {

SE2 planar(const engine::Pose& p) { return SE2::from_se3(SE3(p.orientation, p.position)); }

// One run: the NEES of every `every`-th published pose, and the position error at each.
void one_run(const ConsistencyOptions& o, uint64_t seed, std::vector<double>& nees, std::vector<double>& time_s,
             std::vector<double>& position_error) {
  SimulationOptions sim = o.simulation;
  sim.seed = seed;
  const auto log = (std::filesystem::temp_directory_path() /
                    ("sextant_nees_" + std::to_string(::getpid()) + "_" + std::to_string(seed) + ".lcm"))
                       .string();
  SimulationSummary summary;
  {
    runtime::LogWriter w(log);
    summary = simulate(sim, w);
  }
  runtime::LogDamage damage;
  const auto records = runtime::LogReader::read_all(log, &damage);
  std::remove(log.c_str());
  // The log was written just above: damage is a disk problem, and a run with events missing would be misread as an
  // inconsistent filter.
  if (damage.damaged() || damage.truncated_tail_bytes > 0)
    throw std::runtime_error(log + ": the simulated log read back damaged: " + damage.summary());
  engine::FilterConfig cfg = o.filter;
  cfg.slam = o.slam;
  cfg.map.clear();
  std::vector<engine::Event> events;
  for (const auto& r : records) {
    if (r.channel == "GROUND_TRUTH" && !o.slam) {
      sextant::truth_t t;
      if (runtime::decode_message(r.data, t) && t.kind == "landmark")
        cfg.map.push_back({t.id, t.position[0], t.position[1]});
    } else if (r.channel == "ODOMETRY" || r.channel == "LANDMARKS") {
      auto d = runtime::decode_event(
          r.channel == "ODOMETRY" ? runtime::InputKind::kOdometry : runtime::InputKind::kLandmarks, r.data.data(),
          r.data.size());
      if (auto* e = std::get_if<engine::Event>(&d)) events.push_back(*e);
    }
  }
  std::map<int64_t, engine::Pose> truth(summary.robot_truth.begin(), summary.robot_truth.end());
  engine::FilterStage stage(cfg);
  int64_t published = 0;
  size_t sample = 0;
  for (const auto& e : events) {
    stage.handle(e, [&](engine::Output out) {
      const auto& f = std::get<engine::FusedPose>(out);
      if (published++ % o.every != 0) return;
      double n = 0, position2 = 0;
      if (f.planar) {
        const Eigen::Vector3d err = planar(f.pose).between(planar(truth.at(f.utime))).log();
        const Eigen::Matrix3d P = planar_block(f.covariance);
        n = err.dot(P.ldlt().solve(err));
        position2 = err.head<2>().squaredNorm();
      } else {
        const engine::Pose& t = truth.at(f.utime);
        const SE3::Vector6 err = SE3(f.pose.orientation, f.pose.position).between(SE3(t.orientation, t.position)).log();
        n = err.dot(f.covariance.ldlt().solve(err));
        position2 = (t.position - f.pose.position).squaredNorm();
      }
      if (sample >= nees.size()) {
        nees.push_back(0), position_error.push_back(0);
        time_s.push_back(static_cast<double>(f.utime - sim.start_utime) * 1e-6);
      }
      nees[sample] += n;
      position_error[sample] += position2;
      ++sample;
    });
  }
}

}  // namespace

ConsistencyResult pose_nees_over_runs(const ConsistencyOptions& o) {
  if (o.runs < 1 || o.every < 1) throw std::invalid_argument("consistency: runs and every must be positive");
  ConsistencyResult out;
  std::vector<double> sum, sq;
  for (int r = 0; r < o.runs; ++r) one_run(o, o.first_seed + static_cast<uint64_t>(r), sum, out.time_s, sq);
  const double N = o.runs;
  const int dof = o.simulation.scenario == Scenario::kPlanar ? 3 : 6;
  out.lower = assoc::chi2_quantile(dof * o.runs, 0.025) / N;
  out.upper = assoc::chi2_quantile(dof * o.runs, 0.975) / N;
  int inside = 0;
  for (double s : sum) {
    out.anees.push_back(s / N);
    out.mean_anees += s / N;
    inside += s / N >= out.lower && s / N <= out.upper;
  }
  if (!out.anees.empty()) {
    out.mean_anees /= static_cast<double>(out.anees.size());
    out.fraction_inside = inside / static_cast<double>(out.anees.size());
    out.final_position_rmse = std::sqrt(sq.back() / N);
  }
  return out;
}

}  // namespace sextant::tools
