// sextant simulate SCENARIO -o OUT.lcm [--seed N] [--duration S] [--tum-out GT.txt] [--unknown-ids]
//                  [--clutter N] [--clutter-region XMIN YMIN ZMIN XMAX YMAX ZMAX] ...
#include "cli/command.hpp"
#include "sim/simulator.hpp"
#include "eval/trajectory_io.hpp"

#include <cstdio>

namespace {

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
      cmd->callback([=] {
        o->scenario = sextant::tools::scenario_from_name(*scenario);
        if (!region->empty()) {
          o->clutter_region_min.assign(region->begin(), region->begin() + 3);
          o->clutter_region_max.assign(region->begin() + 3, region->end());
        }
        std::string gt = *tum;
        if (gt.empty()) {
          gt = *out;
          if (gt.size() > 4 && gt.compare(gt.size() - 4, 4, ".lcm") == 0) gt.resize(gt.size() - 4);
          gt += "_gt.txt";
        }
        sextant::runtime::LogWriter writer(*out);
        const auto s = sextant::tools::simulate(*o, writer);
        writer.flush();
        std::vector<sextant::tools::StampedPose> truth;
        truth.reserve(s.robot_truth.size());
        for (const auto& [utime, pose] : s.robot_truth) truth.push_back({static_cast<double>(utime) * 1e-6, pose});
        sextant::tools::write_tum(gt, truth);
        std::printf(
            "%s: %lld odometry, %lld landmark messages (%lld sightings), %lld bearing scans (%lld detections, "
            "%lld false alarms), %lld loop closures, %lld truth; ground truth in %s\n",
            out->c_str(), (long long)s.odometry, (long long)s.landmark_messages, (long long)s.landmark_observations,
            (long long)s.bearing_scans, (long long)s.detections, (long long)s.false_alarms, (long long)s.loop_closures,
            (long long)s.truth, gt.c_str());
        if (s.imu > 0 || s.gnss > 0)
          std::printf("%lld IMU samples, %lld GNSS fixes (%lld multipath outliers)\n", (long long)s.imu,
                      (long long)s.gnss, (long long)s.gnss_outliers);
      });
    }};

}  // namespace
