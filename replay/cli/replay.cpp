// sextant replay LOG.lcm --config FILE [--tum-out F] [--kitti-out F] [--g2o-out F] [--out-log F] [--json]
//                                      [--realtime [--speed X] [--lcm-url URL]]
#include "daemon/runtime/lcm_log.hpp"
#include "replay/cli/command.hpp"
#include "replay/json_writer.hpp"
#include "replay/replay_driver.hpp"
#include "replay/realtime_player.hpp"
#include "replay/report.hpp"
#include "replay/trajectory_io.hpp"

#include <algorithm>
#include <cstdio>
#include <unistd.h>

namespace {

using namespace sextant;

struct Options {
  std::string log, config, tum_out, kitti_out, g2o_out, out_log, estimator, report;
  bool json = false;
  bool realtime = false;
  bool tolerate_damage = false;
  double speed = 1.0;
  std::string lcm_url;
};

std::vector<replay::StampedPose> trajectory_of(const std::vector<engine::FusedPose>& poses) {
  std::vector<replay::StampedPose> out;
  out.reserve(poses.size());
  for (const auto& p : poses) out.push_back({static_cast<double>(p.utime) * 1e-6, p.pose});
  return out;
}

// A one-line progress bar with rate and ETA, on a terminal only.
class ProgressBar {
 public:
  explicit ProgressBar(bool enabled) : enabled_(enabled), start_(std::chrono::steady_clock::now()) {}
  void operator()(int64_t done, int64_t total) {
    if (!enabled_ || total <= 0) return;
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    const double rate = elapsed > 0 ? static_cast<double>(done) / elapsed : 0;
    const double eta = rate > 0 ? static_cast<double>(total - done) / rate : 0;
    const int width = 30, filled = static_cast<int>(width * done / total);
    std::fprintf(stderr, "\r[%-*s] %3d%% %8.0f msg/s ETA %5.1f s", width, std::string(static_cast<size_t>(filled), '#').c_str(),
                 static_cast<int>(100 * done / total), rate, eta);
    if (done == total) std::fprintf(stderr, "\n");
  }

 private:
  bool enabled_;
  std::chrono::steady_clock::time_point start_;
};

void print_json(const Options& o, const replay::ReplayResult& r, const std::string& estimator) {
  replay::JsonWriter j;
  j.begin_object();
  j.field("log", o.log);
  j.field("records", r.records);
  j.key("log_damage").begin_object();
  j.field("corrupt_events", r.log_damage.bad_events).field("skipped_bytes", r.log_damage.skipped_bytes);
  j.field("missing_event_numbers", r.log_damage.missing_event_numbers);
  j.field("truncated_tail_bytes", r.log_damage.truncated_tail_bytes);
  j.end_object();
  j.field("primary_estimator", r.primary_estimator);
  j.field("duration_s", static_cast<double>(r.last_utime - r.first_utime) * 1e-6);
  j.field("wall_seconds", r.wall_seconds);
  j.field("realtime_factor", r.wall_seconds > 0 ? static_cast<double>(r.last_utime - r.first_utime) * 1e-6 / r.wall_seconds : 0.0);
  j.key("inputs").begin_object();
  for (const auto& [channel, c] : r.channels) {
    j.key(channel).begin_object();
    j.field("received", c.received).field("decoded", c.decoded).field("rejected", c.rejected).field("lost", c.lost);
    j.key("reasons").begin_object();
    for (const auto& [reason, n] : c.reasons) j.field(reason, n);
    j.end_object();
    j.end_object();
  }
  j.end_object();
  j.key("published").begin_object();
  for (const auto& [channel, n] : r.published_counts) j.field(channel, n);
  j.end_object();
  j.key("stages").begin_array();
  for (const auto& s : r.stages) {
    j.begin_object();
    j.field("name", s.name).field("processed", s.processed);
    std::vector<double> l = s.latency_ms;
    std::sort(l.begin(), l.end());
    auto pct = [&](double p) { return l.empty() ? 0.0 : l[std::min(l.size() - 1, static_cast<size_t>(p * static_cast<double>(l.size())))]; };
    j.field("latency_ms_p50", pct(0.5)).field("latency_ms_p99", pct(0.99)).field("latency_ms_max", l.empty() ? 0.0 : l.back());
    j.key("counters").begin_object();
    for (const auto& [name, v] : s.counters) j.field(name, v);
    j.end_object();
    j.end_object();
  }
  j.end_array();
  const auto it = r.fused_poses.find(estimator);
  j.field("fused_poses", it == r.fused_poses.end() ? int64_t{0} : static_cast<int64_t>(it->second.size()));
  if (it != r.fused_poses.end() && !it->second.empty()) {
    const auto& last = it->second.back();
    j.key("final_pose").begin_object();
    j.field("utime", last.utime);
    j.field("position", std::vector<double>{last.pose.position.x(), last.pose.position.y(), last.pose.position.z()});
    const auto& q = last.pose.orientation;
    j.field("orientation_wxyz", std::vector<double>{q.w(), q.x(), q.y(), q.z()});
    j.end_object();
  }
  j.field("trajectories", static_cast<int64_t>(r.trajectories.size()));
  j.field("targets_messages", static_cast<int64_t>(r.targets.size()));
  j.field("truth_poses", static_cast<int64_t>(r.truth_poses.size()));
  j.end_object();
  std::fputs(j.str().c_str(), stdout);
}

sextant::cli::RegisterCommand reg{"replay", [](CLI::App& app) {
  auto* cmd = app.add_subcommand("replay", "run a log through the engine deterministically (message utime order), "
                                           "or republish it in real time with --realtime");
  auto o = std::make_shared<Options>();
  cmd->add_option("log", o->log, "LCM log")->required()->check(CLI::ExistingFile);
  cmd->add_option("--config", o->config, "sextantd configuration (YAML)");
  cmd->add_option("--tum-out", o->tum_out, "write the primary estimator's fused poses as a TUM trajectory");
  cmd->add_option("--kitti-out", o->kitti_out, "the same as KITTI 3x4 poses");
  cmd->add_option("--g2o-out", o->g2o_out, "the same as a g2o graph");
  cmd->add_option("--out-log", o->out_log, "write everything the engine published to an LCM log");
  cmd->add_option("--estimator", o->estimator, "which estimator's poses to export (default: the primary)");
  cmd->add_flag("--json", o->json, "print a JSON summary on stdout");
  cmd->add_option("--report", o->report, "write an HTML report with plots (and report.json) into this folder");
  cmd->add_flag("--realtime", o->realtime, "republish the log to the live bus at the pace of message utimes");
  cmd->add_option("--speed", o->speed, "playback speed for --realtime (2 = twice as fast)")->check(CLI::PositiveNumber);
  cmd->add_option("--lcm-url", o->lcm_url, "LCM URL for --realtime");
  cmd->add_flag("--tolerate-damage", o->tolerate_damage,
                "exit 0 on a damaged log (corrupt events are skipped and counted either way; without this flag a "
                "damaged log makes the exit code 4)");
  cmd->callback([o] {
    if (o->realtime) {
      const auto n = replay::play_realtime(o->log, o->speed, o->lcm_url);
      if (!o->json) std::printf("republished %lld messages\n", static_cast<long long>(n));
      return;
    }
    config::DaemonConfig cfg;
    if (!o->config.empty()) {
      try {
        cfg = config::load_daemon_config(o->config);
      } catch (const config::ConfigError& e) {
        std::fprintf(stderr, "sextant replay: bad configuration (--config %s): %s\n", o->config.c_str(), e.what());
        throw CLI::RuntimeError(2);
      }
    }
    ProgressBar bar(isatty(STDERR_FILENO) != 0 && !o->json);
    const auto result = replay::replay_log(o->log, cfg, [&bar](int64_t d, int64_t t) { bar(d, t); });
    const std::string estimator = o->estimator.empty() ? result.primary_estimator : o->estimator;
    const auto it = result.fused_poses.find(estimator);
    const std::vector<engine::FusedPose> none;
    const auto traj = trajectory_of(it == result.fused_poses.end() ? none : it->second);
    if (!o->tum_out.empty()) replay::write_tum(o->tum_out, traj);
    if (!o->kitti_out.empty()) replay::write_kitti(o->kitti_out, traj);
    if (!o->g2o_out.empty()) replay::write_g2o_trajectory(o->g2o_out, traj);
    if (!o->out_log.empty()) {
      runtime::LogWriter w(o->out_log);
      for (const auto& m : result.published) w.write_raw(m.utime, m.channel, m.bytes.data(), m.bytes.size());
    }
    if (!o->report.empty()) {
      const auto n = replay::write_report(o->report, result, o->log, estimator);
      if (!o->json) {
        if (n.have_truth) std::printf("ATE %.4f m RMSE (max %.4f m) over %zu poses\n", n.ate_rmse, n.ate_max, n.matched);
        std::printf("report: %s/index.html\n", o->report.c_str());
      }
    }
    if (o->json) {
      print_json(*o, result, estimator);
    } else {
      int64_t rejected = 0;
      for (const auto& [c, counts] : result.channels) rejected += counts.rejected;
      std::printf("replayed %lld log events (%.1f s of data) in %.2f s; %zu %s poses; %lld inputs rejected\n",
                  static_cast<long long>(result.records), static_cast<double>(result.last_utime - result.first_utime) * 1e-6,
                  result.wall_seconds, traj.size(), estimator.c_str(), static_cast<long long>(rejected));
    }
    if (const std::string d = result.log_damage.summary(); !d.empty())
      std::fprintf(stderr, "sextant replay: %s: %s\n", o->log.c_str(), d.c_str());
    if (result.log_damage.damaged() && !o->tolerate_damage) {
      std::fprintf(stderr, "sextant replay: the log is damaged (the good events were replayed); --tolerate-damage "
                           "accepts it\n");
      throw CLI::RuntimeError(4);
    }
  });
}};

}  // namespace
