// sextant replay LOG.lcm --config FILE [--tum-out F] [--kitti-out F] [--g2o-out F] [--out-log F] [--json]
//                                      [--realtime [--speed X] [--lcm-url URL]]
#include "daemon/engine/engine.hpp"
#include "daemon/runtime/lcm_log.hpp"
#include "daemon/runtime/nearest_rank_percentile.hpp"
#include "cli/command.hpp"
#include "cli/log_damage_report.hpp"
#include "daemon/runtime/version.hpp"
#include "report/json_writer.hpp"
#include "replay/replay_driver.hpp"
#include "replay/realtime_player.hpp"
#include "report/report.hpp"
#include "eval/trajectory_io.hpp"
#include "viewer/lcm_mcap.hpp"

#include <malloc.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace {

using namespace sextant;

struct Options {
  std::string log, config, tum_out, kitti_out, g2o_out, out_log, mcap_out, estimator, body, report;
  bool json = false;
  bool realtime = false;
  bool tolerate_damage = false;
  double speed = 1.0;
  double max_gap_s = 10.0;
  double segment_seconds = 0;
  bool single_thread = false;
  std::string lcm_url;
};

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
    std::fprintf(stderr, "\r[%-*s] %3d%% %8.0f msg/s ETA %5.1f s", width,
                 std::string(static_cast<size_t>(filled), '#').c_str(), static_cast<int>(100 * done / total), rate,
                 eta);
    if (done == total) std::fprintf(stderr, "\n");
  }

 private:
  bool enabled_;
  std::chrono::steady_clock::time_point start_;
};

void print_json(const Options& o, const tools::ReplayResult& r, const std::string& estimator) {
  tools::JsonWriter j;
  j.begin_object();
  j.field("version", sextant::version());
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
  j.field("realtime_factor",
          r.wall_seconds > 0 ? static_cast<double>(r.last_utime - r.first_utime) * 1e-6 / r.wall_seconds : 0.0);
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
    auto pct = [&](double p) { return runtime::nearest_rank_percentile(l, p); };
    j.field("latency_ms_p50", pct(0.5)).field("latency_ms_p99", pct(0.99)).field("latency_ms_max", s.latency_max_ms);
    j.key("counters").begin_object();
    for (const auto& [name, v] : s.counters) j.field(name, v);
    j.end_object();
    j.end_object();
  }
  j.end_array();
  const auto count = r.fused_pose_counts.find(estimator);
  j.field("fused_poses", count == r.fused_pose_counts.end() ? int64_t{0} : count->second);
  if (const auto it = r.last_fused_poses.find(estimator); it != r.last_fused_poses.end()) {
    const auto& last = it->second;
    j.key("final_pose").begin_object();
    j.field("utime", last.utime);
    j.field("position", std::vector<double>{last.pose.position.x(), last.pose.position.y(), last.pose.position.z()});
    const auto& q = last.pose.orientation;
    j.field("orientation_wxyz", std::vector<double>{q.w(), q.x(), q.y(), q.z()});
    j.end_object();
  }
  j.field("trajectories", r.trajectory_messages);
  j.field("targets_messages", r.target_messages);
  j.field("truth_poses", static_cast<int64_t>(r.truth_poses.size()));
  if (!r.segments.empty()) {
    j.key("segments").begin_array();
    for (const auto& seg : r.segments) {
      j.begin_object();
      j.field("start_s", seg.start_s).field("data_s", seg.data_s).field("wall_s", seg.wall_s);
      j.field("realtime_factor", seg.wall_s > 0 ? seg.data_s / seg.wall_s : 0.0).field("rss_kb", seg.rss_kb);
      j.key("stages").begin_object();
      for (const auto& st : seg.stages) {
        j.key(st.name).begin_object();
        j.field("events", st.events).field("p50_ms", st.p50_ms).field("p99_ms", st.p99_ms).field("max_ms", st.max_ms);
        j.end_object();
      }
      j.end_object();
      j.key("graph").begin_object();
      for (const auto& [name, v] : seg.graph_counters) j.field(name, v);
      j.end_object();
      j.end_object();
    }
    j.end_array();
  }
  j.end_object();
  std::fputs(j.str().c_str(), stdout);
}

void add_options(CLI::App* cmd, Options& o) {
  cmd->add_option("log", o.log, "LCM log")->required()->check(CLI::ExistingFile);
  cmd->add_option("--config", o.config, "sextantd configuration (YAML)");
  cmd->add_option("--tum-out", o.tum_out, "write the primary estimator's fused poses as a TUM trajectory");
  cmd->add_option("--kitti-out", o.kitti_out, "the same as KITTI 3x4 poses");
  cmd->add_option("--g2o-out", o.g2o_out, "the same as a g2o graph");
  cmd->add_option("--out-log", o.out_log, "write everything the engine published to an LCM log");
  cmd->add_option("--mcap-out", o.mcap_out,
                  "write the log's inputs and everything published to an MCAP file for "
                  "Foxglove (the topics of `sextant foxglove`)");
  cmd->add_option("--estimator", o.estimator, "which estimator's poses to export (default: the primary)");
  cmd->add_option("--body", o.body,
                  "export only this body's poses (a log of several robots interleaves them; default: every body)");
  cmd->add_flag("--json", o.json, "print a JSON summary on stdout");
  cmd->add_option(
         "--segment-seconds", o.segment_seconds,
         "with --json: report each stretch of this many seconds of data time (replay speed, stage times, memory)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--single-thread", o.single_thread,
                "every stage on one thread (by default the graph's stages run on a second one beside the others; "
                "the outputs are the same)");
  cmd->add_option("--report", o.report, "write an HTML report with plots (and report.json) into this folder");
  cmd->add_flag("--realtime", o.realtime, "republish the log to the live bus at the pace of message utimes");
  cmd->add_option("--speed", o.speed, "playback speed for --realtime (2 = twice as fast)")->check(CLI::PositiveNumber);
  cmd->add_option("--max-gap", o.max_gap_s,
                  "for --realtime: a longer stretch of log time between two messages plays as this many seconds")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--lcm-url", o.lcm_url, "LCM URL for --realtime");
  cmd->add_flag("--tolerate-damage", o.tolerate_damage, cli::kTolerateDamageHelp);
}

// --realtime: the log republished on the live bus at the pace of its utimes.
void replay_in_realtime(const Options& o) {
  const auto played = tools::play_realtime(o.log, {o.speed, o.max_gap_s, o.lcm_url});
  if (!o.json) std::printf("republished %lld messages\n", static_cast<long long>(played.published));
  if (played.gaps_shortened > 0)
    std::fprintf(stderr,
                 "sextant replay: %lld gaps longer than --max-gap %g s played as %g s (%.6g s of log time skipped)\n",
                 static_cast<long long>(played.gaps_shortened), o.max_gap_s, o.max_gap_s, played.log_seconds_skipped);
  cli::report_log_damage("sextant replay", o.log, played.damage, o.tolerate_damage);
}

// --config's configuration (the defaults without one); a bad one exits 2 with its place.
config::DaemonConfig load_config(const Options& o) {
  config::DaemonConfig cfg;
  if (o.config.empty()) return cfg;
  try {
    cfg = config::load_daemon_config(o.config);
  } catch (const config::ConfigError& e) {
    std::fprintf(stderr, "sextant replay: bad configuration (--config %s): %s\n", o.config.c_str(), e.what());
    throw CLI::RuntimeError(2);
  }
  return cfg;
}

// The files the replay streams its outputs into as it goes (memory keeps bounded samples for the report and the
// summary): everything published into --out-log and, with the log's inputs, into --mcap-out; the exported
// estimator's poses into the trajectory files.  The callbacks it installs refer to it: it stays in place until closed.
class StreamedOutputs {
 public:
  StreamedOutputs(const Options& o, const config::DaemonConfig& cfg, tools::ReplayOptions& ro) {
    if (!o.out_log.empty()) out_log_ = std::make_unique<runtime::LogWriter>(o.out_log);
    if (!o.mcap_out.empty()) mcap_ = std::make_unique<viewer::ReplayMcapRecorder>(o.log, o.mcap_out);
    if (out_log_ || mcap_)
      ro.on_publish = [this](const std::string& channel, const std::vector<uint8_t>& bytes, int64_t utime) {
        if (out_log_) out_log_->write_raw(utime, channel, bytes.data(), bytes.size());
        if (mcap_) mcap_->published(channel, bytes, utime);
      };
    if (!o.tum_out.empty())
      writers_.push_back(std::make_unique<tools::TrajectoryWriter>(o.tum_out, tools::TrajectoryFormat::kTum));
    if (!o.kitti_out.empty())
      writers_.push_back(std::make_unique<tools::TrajectoryWriter>(o.kitti_out, tools::TrajectoryFormat::kKitti));
    if (!o.g2o_out.empty())
      writers_.push_back(std::make_unique<tools::TrajectoryWriter>(o.g2o_out, tools::TrajectoryFormat::kG2o));
    // The estimator to export is known once the engine is built (the primary one by default): its name is matched
    // against each pose's.
    export_estimator_ = o.estimator;
    export_body_ = o.body;
    if (export_estimator_.empty()) export_estimator_ = engine::Engine(cfg.engine).primary_estimator();
    ro.on_fused_pose = [this](const engine::FusedPose& p) {
      if (p.estimator != export_estimator_ || (!export_body_.empty() && p.source != export_body_)) return;
      for (auto& w : writers_) w->add({static_cast<double>(p.utime) * 1e-6, p.pose});
    };
  }
  StreamedOutputs(const StreamedOutputs&) = delete;
  StreamedOutputs& operator=(const StreamedOutputs&) = delete;

  void close() {
    for (auto& w : writers_) w->close();
    if (out_log_) out_log_->flush();
    if (mcap_) mcap_->close();
  }

 private:
  std::unique_ptr<runtime::LogWriter> out_log_;
  std::unique_ptr<viewer::ReplayMcapRecorder> mcap_;
  std::vector<std::unique_ptr<tools::TrajectoryWriter>> writers_;
  std::string export_estimator_, export_body_;
};

// The one line without --json: events, data time, wall time, poses exported, inputs rejected.
void print_summary_line(const tools::ReplayResult& result, const std::string& estimator) {
  const auto counted = result.fused_pose_counts.find(estimator);
  const int64_t exported = counted == result.fused_pose_counts.end() ? 0 : counted->second;
  int64_t rejected = 0;
  for (const auto& [c, counts] : result.channels) rejected += counts.rejected;
  std::printf("replayed %lld log events (%.1f s of data) in %.2f s; %zu %s poses; %lld inputs rejected\n",
              static_cast<long long>(result.records),
              static_cast<double>(result.last_utime - result.first_utime) * 1e-6, result.wall_seconds,
              static_cast<size_t>(exported), estimator.c_str(), static_cast<long long>(rejected));
}

// Stages that failed on an event (and recovered: the replay went on), on stderr.
void report_stage_failures(const tools::ReplayResult& result) {
  for (const auto& s : result.stages)
    if (s.failures > 0)
      std::fprintf(stderr,
                   "sextant replay: stage '%s' failed on %lld event(s) and recovered from %lld (the replay went on); "
                   "last: %s\n",
                   s.name.c_str(), static_cast<long long>(s.failures), static_cast<long long>(s.recoveries),
                   s.last_failure.c_str());
}

// glibc raises its mmap threshold each time a large block is freed (up to 32 MB), after which such blocks come from
// the heaps, where the graph's rebuilds leave them scattered; with replay's second thread in its own arena the
// resident memory then grew in steps of 20 MB.  A fixed threshold keeps blocks of 1 MB and more in their own
// mappings, returned when freed: the 3-minute 8-robot replay's peak RSS 128-139 -> 94-96 MB at the same speed.
void keep_large_blocks_mapped() { mallopt(M_MMAP_THRESHOLD, 1 << 20); }

void run(const Options& o) {
  if (o.realtime) return replay_in_realtime(o);
  keep_large_blocks_mapped();
  const config::DaemonConfig cfg = load_config(o);
  ProgressBar bar(isatty(STDERR_FILENO) != 0 && !o.json);
  tools::ReplayOptions ro;
  ro.max_kept = 8192;
  ro.segment_seconds = o.segment_seconds;
  ro.pipelined = !o.single_thread;
  StreamedOutputs outputs(o, cfg, ro);
  const auto result = tools::replay_log(
      o.log, cfg, [&bar](int64_t d, int64_t t) { bar(d, t); }, ro);
  const std::string estimator = o.estimator.empty() ? result.primary_estimator : o.estimator;
  outputs.close();
  if (!o.report.empty()) {
    const auto n = tools::write_report(o.report, result, o.log, estimator);
    if (!o.json) {
      if (n.have_truth) std::printf("ATE %.4f m RMSE (max %.4f m) over %zu poses\n", n.ate_rmse, n.ate_max, n.matched);
      std::printf("report: %s/index.html\n", o.report.c_str());
    }
  }
  if (o.json)
    print_json(o, result, estimator);
  else
    print_summary_line(result, estimator);
  report_stage_failures(result);
  cli::report_log_damage("sextant replay", o.log, result.log_damage, o.tolerate_damage);
}

sextant::cli::RegisterCommand reg{"replay", [](CLI::App& app) {
                                    auto* cmd = app.add_subcommand(
                                        "replay",
                                        "run a log through the engine deterministically (message utime order), "
                                        "or republish it in real time with --realtime");
                                    auto o = std::make_shared<Options>();
                                    add_options(cmd, *o);
                                    cmd->callback([o] { run(*o); });
                                  }};

}  // namespace
