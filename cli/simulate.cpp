// sextant simulate SCENARIO -o OUT.lcm [--seed N] [--duration S] [--tum-out GT.txt] [--unknown-ids]
//                  [--clutter N] [--clutter-region XMIN YMIN ZMIN XMAX YMAX ZMAX] ...
//                  [--robots N [--wrong-loops SHARE [--omit-wrong-loops]] [--gt-prefix PREFIX] [--config-out FLEET.yaml]]
#include "cli/command.hpp"
#include "sim/simulator.hpp"
#include "eval/trajectory_io.hpp"

#include <cstdio>
#include <stdexcept>

namespace {

// OUT.lcm without its extension, plus `suffix`.
std::string beside(const std::string& out, const std::string& suffix) {
  std::string s = out;
  if (s.size() > 4 && s.compare(s.size() - 4, 4, ".lcm") == 0) s.resize(s.size() - 4);
  return s + suffix;
}

std::vector<sextant::tools::StampedPose> stamped(const std::vector<std::pair<int64_t, sextant::engine::Pose>>& poses) {
  std::vector<sextant::tools::StampedPose> out;
  out.reserve(poses.size());
  for (const auto& [utime, pose] : poses) out.push_back({static_cast<double>(utime) * 1e-6, pose});
  return out;
}

// The config lines that tell the daemon which landmark ids are the fleet's robots.
std::string markers_yaml(const std::map<int64_t, std::string>& markers) {
  std::string m;
  for (const auto& [id, source] : markers) m += (m.empty() ? "" : ", ") + std::to_string(id) + ": " + source;
  return "engine:\n  graph:\n    fleet:\n      enabled: true\n      markers: {" + m + "}\n";
}

// A fleet's ground truth (PREFIX robotN.txt per robot, PREFIX landmarks.txt) and its markers (printed, and with
// `config_out` written as a config file to merge into the daemon's).
void write_fleet_outputs(const sextant::tools::SimulationOptions& o, const sextant::tools::SimulationSummary& s,
                         const std::string& prefix, const std::string& config_out) {
  for (const auto& [source, truth] : s.fleet_truth) sextant::tools::write_tum(prefix + source + ".txt", stamped(truth));
  sextant::tools::write_landmarks(prefix + "landmarks.txt", s.landmarks,
                                  o.scenario == sextant::tools::Scenario::kPlanar);
  const std::string yaml = markers_yaml(s.markers);
  if (!config_out.empty()) {
    std::FILE* f = std::fopen(config_out.c_str(), "w");
    if (f == nullptr || std::fputs(yaml.c_str(), f) < 0 || std::fclose(f) != 0)
      throw std::runtime_error("cannot write " + config_out);
  }
  std::printf(
      "%d robots: %lld robot sightings, %lld inter-robot loop closures (%lld wrong); ground truth in "
      "%sROBOT.txt and %slandmarks.txt; markers (config%s):\n%s",
      o.robots, (long long)s.robot_sightings, (long long)s.inter_robot_loops, (long long)s.wrong_loops, prefix.c_str(),
      prefix.c_str(), config_out.empty() ? "" : (" in " + config_out).c_str(), yaml.c_str());
}

void add_fleet_options(CLI::App* cmd, sextant::tools::SimulationOptions& o, std::string& gt_prefix,
                       std::string& config_out) {
  cmd->add_option("--robots", o.robots,
                  "a fleet of N robots (robot1..robotN) in one world: each odometry in its own frame, robot "
                  "sightings by marker id 1000000+N, inter-robot loop closures")
      ->check(CLI::Range(1, 1000));
  cmd->add_option("--wrong-loops", o.wrong_loops, "fleet: share of the inter-robot loop closures that are wrong")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_flag("--omit-wrong-loops", o.omit_wrong_loops,
                "fleet: draw the wrong loops but do not write them (the same run without its wrong loops)");
  cmd->add_option("--gt-prefix", gt_prefix,
                  "fleet: ground truth in PREFIX robotN.txt (TUM) and PREFIX landmarks.txt (default: OUT with "
                  "_gt_)");
  cmd->add_option("--config-out", config_out, "fleet: write the markers as a config file (engine.graph.fleet)");
}

sextant::cli::RegisterCommand reg{
    "simulate", [](CLI::App& app) {
      auto* cmd = app.add_subcommand("simulate",
                                     "write a synthetic run (odometry, landmarks, passive bearings, loop "
                                     "closures) with its ground truth to an LCM log");
      auto o = std::make_shared<sextant::tools::SimulationOptions>();
      auto out = std::make_shared<std::string>();
      auto tum = std::make_shared<std::string>();
      auto region = std::make_shared<std::vector<double>>();
      auto scenario = std::make_shared<std::string>();
      auto gt_prefix = std::make_shared<std::string>(), config_out = std::make_shared<std::string>();
      cmd->add_option("scenario", *scenario, "planar (2D robot) or spatial (3D)")
          ->required()
          ->check(CLI::IsMember(sextant::tools::scenario_names()));
      cmd->add_option("-o,--output", *out, "output LCM log")->required();
      cmd->add_option("--seed", o->seed, "random seed (the same seed gives the same log, byte for byte)");
      cmd->add_option("--duration", o->duration_s, "seconds of robot time")->check(CLI::PositiveNumber);
      cmd->add_option("--tum-out", *tum, "ground-truth trajectory in TUM format (default: OUT with _gt.txt)");
      cmd->add_flag("--unknown-ids", o->unknown_ids, "landmark sightings carry id -1 (data association needed)");
      cmd->add_option("--landmarks", o->landmarks, "number of point landmarks")->check(CLI::NonNegativeNumber);
      cmd->add_option("--sensors", o->sensors, "number of passive sensors")->check(CLI::Range(2, 64));
      cmd->add_option("--targets", o->targets, "number of moving targets")->check(CLI::NonNegativeNumber);
      cmd->add_option("--pd", o->p_detect, "detection probability of the passive sensors")->check(CLI::Range(0.0, 1.0));
      cmd->add_option("--clutter", o->clutter, "mean false alarms per sensor per scan")->check(CLI::NonNegativeNumber);
      cmd->add_option("--clutter-region", *region,
                      "false alarms in each sensor's field of view over the box XMIN YMIN ZMIN XMAX YMAX ZMAX (m) "
                      "instead of over all azimuths (match it with association.region_min/max in the daemon's config)")
          ->expected(6);
      cmd->add_option("--odometry-rate", o->odometry_rate_hz, "Hz")->check(CLI::PositiveNumber);
      cmd->add_option("--odometry-noise", o->odometry_trans_noise, "translation noise, m per m travelled");
      cmd->add_option("--speed", o->speed, "m/s")->check(CLI::PositiveNumber);
      cmd->add_option("--imu-rate", o->imu_rate_hz, "IMU samples on IMU, Hz (0: none)")->check(CLI::NonNegativeNumber);
      cmd->add_option("--gnss-rate", o->gnss_rate_hz, "GNSS fixes on GNSS, Hz (0: none)")
          ->check(CLI::NonNegativeNumber);
      cmd->add_option("--gnss-outage", o->gnss.outage_duration_s,
                      "seconds without GNSS at the end of every --gnss-outage-period")
          ->check(CLI::NonNegativeNumber);
      cmd->add_option("--gnss-outage-period", o->gnss.outage_period_s, "s")->check(CLI::NonNegativeNumber);
      cmd->add_option("--gnss-outliers", o->gnss.outlier_probability, "probability of a multipath outlier per fix")
          ->check(CLI::Range(0.0, 1.0));
      cmd->add_option("--loop-distance", o->loop_distance,
                      "loop closures when the robot returns within this distance, m "
                      "(0: none, e.g. when a matcher answers the daemon's requests instead)")
          ->check(CLI::NonNegativeNumber);
      add_fleet_options(cmd, *o, *gt_prefix, *config_out);
      cmd->callback([=] {
        o->scenario = sextant::tools::scenario_from_name(*scenario);
        if (!region->empty()) {
          o->clutter_region_min.assign(region->begin(), region->begin() + 3);
          o->clutter_region_max.assign(region->begin() + 3, region->end());
        }
        const bool fleet = o->robots > 1;
        const std::string gt = !tum->empty() ? *tum : beside(*out, "_gt.txt");
        const std::string prefix = !gt_prefix->empty() ? *gt_prefix : beside(*out, "_gt_");
        sextant::runtime::LogWriter writer(*out);
        sextant::tools::SimulationSummary s;
        try {
          s = sextant::tools::simulate(*o, writer);
          writer.flush();
          if (fleet) write_fleet_outputs(*o, s, prefix, *config_out);
        } catch (const std::exception& e) {
          std::fprintf(stderr, "sextant simulate: %s\n", e.what());
          throw CLI::RuntimeError(2);
        }
        if (!fleet) sextant::tools::write_tum(gt, stamped(s.robot_truth));
        std::printf(
            "%s: %lld odometry, %lld landmark messages (%lld sightings), %lld bearing scans (%lld detections, "
            "%lld false alarms), %lld loop closures, %lld truth; ground truth in %s\n",
            out->c_str(), (long long)s.odometry, (long long)s.landmark_messages, (long long)s.landmark_observations,
            (long long)s.bearing_scans, (long long)s.detections, (long long)s.false_alarms, (long long)s.loop_closures,
            (long long)s.truth, fleet ? (prefix + "*").c_str() : gt.c_str());
        if (s.imu > 0 || s.gnss > 0)
          std::printf("%lld IMU samples, %lld GNSS fixes (%lld multipath outliers)\n", (long long)s.imu,
                      (long long)s.gnss, (long long)s.gnss_outliers);
      });
    }};

}  // namespace
