// sextant convert g2o FILE -o OUT.lcm [--gt-out GT.txt] | mrclam DIR --robot N -o OUT.lcm [--gt-out GT.txt]
//                 | mrclam DIR --robots 1-5 -o OUT.lcm [--gt-out PREFIX]
//                 | tum GT.txt -o OUT.lcm [--seed N ...] | euroc DIR -o OUT.lcm [--gt-out GT.txt]
//                 | rosbag FILE.bag -o OUT.lcm [--topic TOPIC=CHANNEL]... [--frame FRAME=BODY]... [--yaw-free TOPIC]...
#include "cli/command.hpp"
#include "cli/convert_command.hpp"
#include "convert/euroc_converter.hpp"
#include "convert/g2o_converter.hpp"
#include "convert/mrclam_converter.hpp"
#include "cli/rosbag_plugin/rosbag_plugin.hpp"
#include "convert/tum_converter.hpp"
#include "eval/trajectory_io.hpp"

#include <cstdio>
#include <map>
#include <stdexcept>
#include <vector>

namespace {

using namespace sextant::tools;

// "KEY=VALUE" arguments (--topic, --frame) as a map; std::invalid_argument naming the option for a malformed one.
std::map<std::string, std::string> key_values(const std::vector<std::string>& args, const char* option) {
  std::map<std::string, std::string> out;
  for (const std::string& a : args) {
    const size_t eq = a.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == a.size())
      throw std::invalid_argument(std::string(option) + " " + a + ": expected NAME=VALUE");
    out[a.substr(0, eq)] = a.substr(eq + 1);
  }
  return out;
}

std::string counts(const std::map<std::string, int64_t>& m) {
  std::string s;
  for (const auto& [k, v] : m) s += (s.empty() ? "" : ", ") + k + " " + std::to_string(v);
  return s.empty() ? "none" : s;
}

void add_mrclam(CLI::App* cmd) {
  auto* mr = cmd->add_subcommand("mrclam",
                                 "a UTIAS MRCLAM data set folder -> one robot's (--robot) or a fleet's (--robots) "
                                 "odometry, landmark (and robot) sightings and truth");
  auto dir = std::make_shared<std::string>(), out = std::make_shared<std::string>(),
       gt = std::make_shared<std::string>(), robots = std::make_shared<std::string>();
  auto robot = std::make_shared<int>(1);
  mr->add_option("dir", *dir, "folder with Barcodes.dat, Landmark_Groundtruth.dat, RobotN_*.dat")
      ->required()
      ->check(CLI::ExistingDirectory);
  auto* one = mr->add_option("--robot", *robot, "one robot, 1 to 5, its odometry starting on its ground truth")
                  ->check(CLI::Range(1, 5));
  auto* fleet = mr->add_option("--robots", *robots,
                               "a fleet in one log, e.g. 1-5 or 1,3: each robot's odometry in its own frame, robot "
                               "sightings kept with the seen robot's number as id");
  one->excludes(fleet);
  mr->add_option("-o,--output", *out, "output LCM log")->required();
  mr->add_option("--gt-out", *gt,
                 "--robot: the robot's ground truth as a TUM file; --robots: a prefix P, written P robotN.txt (TUM) "
                 "per robot and P landmarks.txt (id x y)");
  auto o = std::make_shared<MrclamOptions>();
  mr->add_option("--command-delay", o->command_delay_s,
                 "seconds between a velocity command's stamp and the motion it causes")
      ->check(CLI::Range(-1.0, 1.0));
  mr->add_option("--range-sigma-per-metre", o->range_sigma_per_metre, "range noise, m per m of range")
      ->check(CLI::PositiveNumber);
  mr->add_option("--bearing-sigma", o->bearing_sigma, "bearing noise, rad")->check(CLI::PositiveNumber);
  mr->callback([=] {
    sextant::cli::convert_guarded("mrclam", [&] {
      if (one->count() == 0 && fleet->count() == 0) throw std::invalid_argument("give --robot N or --robots LIST");
      const auto r = fleet->count() ? convert_mrclam_fleet(*dir, parse_mrclam_robots(*robots), *out, *gt, *o)
                                    : convert_mrclam(*dir, *robot, *out, *gt, *o);
      std::printf(
          "%s: %lld odometry, %lld landmark messages (%lld landmark sightings, %lld of %lld robot sightings; %lld "
          "unknown barcodes left out), %lld truth\n",
          out->c_str(), (long long)r.odometry, (long long)r.landmark_messages, (long long)r.landmark_observations,
          (long long)r.robot_sightings_kept, (long long)r.robot_sightings, (long long)r.unknown_barcodes,
          (long long)r.truth);
    });
  });
}

void add_euroc(CLI::App* cmd) {
  auto* eu =
      cmd->add_subcommand("euroc", "a EuRoC MAV folder (ASL CSV: imu0, ground truth) -> imu_t samples and truth");
  auto dir = std::make_shared<std::string>(), out = std::make_shared<std::string>(),
       gt = std::make_shared<std::string>();
  auto opt = std::make_shared<EurocConversionOptions>();
  eu->add_option("dir", *dir, "folder with imu0/data.csv (or mav0/imu0/data.csv)")
      ->required()
      ->check(CLI::ExistingDirectory);
  eu->add_option("-o,--output", *out, "output LCM log")->required();
  eu->add_option("--gt-out", *gt, "the ground truth as a TUM trajectory");
  eu->add_option("--source", opt->source, "body name (imu_t.source)");
  eu->add_option("--channel", opt->imu_channel, "IMU channel");
  eu->callback([=] {
    sextant::cli::convert_guarded("euroc", [&] {
      const auto r = convert_euroc(*dir, *out, *gt, *opt);
      std::printf("%s: %lld imu samples, %lld truth\n", out->c_str(), (long long)r.imu, (long long)r.truth);
    });
  });
}

void add_rosbag(CLI::App* cmd) {
  auto* rb = cmd->add_subcommand(
      "rosbag", "a ROS 1 bag (Imu, Odometry, NavSatFix, PoseWithCovarianceStamped) -> sextant's messages");
  auto in = std::make_shared<std::string>(), out = std::make_shared<std::string>();
  auto topics = std::make_shared<std::vector<std::string>>(), frames = std::make_shared<std::vector<std::string>>();
  auto yaw_free = std::make_shared<std::vector<std::string>>();
  rb->add_option("file", *in, "ROS 1 bag")->required()->check(CLI::ExistingFile);
  rb->add_option("-o,--output", *out, "output LCM log")->required();
  rb->add_option("--topic", *topics,
                 "TOPIC=CHANNEL; when given, only the listed topics are converted (default: IMU, "
                 "ODOMETRY, GNSS by type)");
  rb->add_option("--frame", *frames, "FRAME=BODY: a ROS frame_id's body name (default: the frame_id itself)");
  rb->add_option("--yaw-free", *yaw_free, "an IMU topic whose orientation has no meaningful yaw");
  rb->callback([=] {
    sextant::cli::convert_guarded("rosbag", [&] {
      RosbagConversionOptions o;
      o.channels = key_values(*topics, "--topic");
      o.bodies = key_values(*frames, "--frame");
      o.yaw_free_topics.insert(yaw_free->begin(), yaw_free->end());
      const auto r = sextant::cli::convert_rosbag_via_module(*in, *out, o);
      std::printf("%s: written %s; skipped %s; dropped (non-finite) %s\n", out->c_str(), counts(r.written).c_str(),
                  counts(r.skipped).c_str(), counts(r.dropped).c_str());
      for (const auto& [topic, first] : r.first_dropped) std::printf("  %s\n", first.c_str());
    });
  });
}

sextant::cli::RegisterCommand reg{
    "convert", [](CLI::App& app) {
      auto* cmd = sextant::cli::convert_command(app);

      auto* g2o = cmd->add_subcommand("g2o", "a g2o pose graph -> odometry and loop closures");
      auto g_in = std::make_shared<std::string>(), g_out = std::make_shared<std::string>(),
           g_gt = std::make_shared<std::string>();
      auto g_opt = std::make_shared<G2oConversionOptions>();
      g2o->add_option("file", *g_in, "g2o file")->required()->check(CLI::ExistingFile);
      g2o->add_option("-o,--output", *g_out, "output LCM log")->required();
      g2o->add_option("--gt-out", *g_gt, "write the file's vertex estimates as a TUM trajectory");
      g2o->add_option("--period", g_opt->period_us, "microseconds between vertices")->check(CLI::PositiveNumber);
      g2o->callback([=] {
        sextant::cli::convert_guarded("g2o", [&] {
          const auto r = convert_g2o(*g_in, *g_out, *g_gt, *g_opt);
          std::printf("%s: %lld odometry, %lld loop closures (%lld edges of other kinds skipped)\n", g_out->c_str(),
                      (long long)r.odometry, (long long)r.loop_closures, (long long)r.skipped_edges);
        });
      });

      add_mrclam(cmd);

      auto* tum = cmd->add_subcommand("tum", "TUM ground truth -> noisy, drifting odometry (plus the ground truth)");
      auto t_in = std::make_shared<std::string>(), t_out = std::make_shared<std::string>(),
           t_gt = std::make_shared<std::string>();
      auto t_opt = std::make_shared<TumConversionOptions>();
      tum->add_option("file", *t_in, "ground truth, TUM format")->required()->check(CLI::ExistingFile);
      tum->add_option("-o,--output", *t_out, "output LCM log")->required();
      tum->add_option("--gt-out", *t_gt, "copy the ground truth (TUM) here");
      tum->add_option("--seed", t_opt->seed, "random seed");
      tum->add_option("--noise-trans", t_opt->trans_noise, "translation noise, m per sqrt(m) travelled (per axis)");
      tum->add_option("--noise-rot", t_opt->rot_noise, "rotation noise, rad per sqrt(rad) turned (per axis)");
      tum->add_option("--frame-rate", t_opt->frame_rate_hz, "odometry rate, Hz (0: every ground-truth sample)");
      tum->add_option("--drift-yaw", t_opt->yaw_drift, "heading bias, rad per m travelled");
      tum->add_option("--drift-scale", t_opt->scale_drift, "translation scale error");
      tum->callback([=] {
        sextant::cli::convert_guarded("tum", [&] {
          const auto r = convert_tum(*t_in, *t_out, *t_opt);
          if (!t_gt->empty()) sextant::tools::write_tum(*t_gt, sextant::tools::read_tum(*t_in));
          std::printf("%s: %lld odometry messages with ground truth\n", t_out->c_str(), (long long)r.odometry);
        });
      });

      add_euroc(cmd);
      add_rosbag(cmd);
    }};

}  // namespace
