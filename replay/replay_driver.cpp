#include "replay/replay_driver.hpp"

#include "daemon/engine/engine.hpp"
#include "daemon/engine/guarded_handle.hpp"
#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/intake.hpp"
#include "daemon/runtime/lcm_log.hpp"
#include "daemon/runtime/publisher.hpp"
#include "replay/even_sample.hpp"
#include "daemon/runtime/nearest_rank_percentile.hpp"

#include <sextant/truth_t.hpp>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <chrono>
#include <numeric>

namespace sextant::replay {

namespace {

/// Targets messages a bounded replay keeps (the newest): what the report plots (the last 20 scans) and a margin.
constexpr size_t kNewestTargetsKept = 64;

/// The process's resident set size in KB (VmRSS of /proc/self/status), 0 where unavailable.
int64_t resident_kb() {
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::atoll(line.c_str() + 6);
  return 0;
}

}  // namespace

std::optional<int64_t> peek_utime(const std::vector<uint8_t>& b) {
  if (b.size() < 16) return std::nullopt;
  uint64_t v = 0;
  for (int i = 8; i < 16; ++i) v = (v << 8) | b[static_cast<size_t>(i)];  // LCM encodes big-endian
  return static_cast<int64_t>(v);
}

ReplayResult replay_log(const std::string& log_path, const config::DaemonConfig& cfg, const Progress& progress,
                        const ReplayOptions& options) {
  const auto wall_start = std::chrono::steady_clock::now();
  // Pass 1: the order.  By message utime, ties in file order; records that are not ours (or too short to carry a
  // utime) keep their log stamp so that they still get counted.  rank[i]: the turn of the file's i-th record.  The
  // reader skips damaged events (and reports them) the same way in both passes.
  std::vector<std::pair<int64_t, uint32_t>> keys;
  runtime::LogDamage damage;
  {
    runtime::LogReader reader(log_path);
    while (auto r = reader.next()) keys.emplace_back(peek_utime(r->data).value_or(r->timestamp), static_cast<uint32_t>(keys.size()));
    damage = reader.damage();
  }
  std::stable_sort(keys.begin(), keys.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<uint32_t> rank(keys.size());
  for (size_t turn = 0; turn < keys.size(); ++turn) rank[keys[turn].second] = static_cast<uint32_t>(turn);
  keys = {};

  ReplayResult result;
  result.log_damage = std::move(damage);
  result.records = static_cast<int64_t>(rank.size());
  engine::Engine engine(cfg.engine);
  result.primary_estimator = engine.primary_estimator();

  runtime::ChannelStats stats;
  runtime::Intake intake(stats, {}, runtime::intake_options(cfg, /*live=*/false));
  const auto& ch = cfg.channels;
  intake.add_channel(ch.full(ch.odometry), runtime::InputKind::kOdometry);
  intake.add_channel(ch.full(ch.landmarks), runtime::InputKind::kLandmarks);
  intake.add_channel(ch.full(ch.bearings), runtime::InputKind::kBearings);
  intake.add_channel(ch.full(ch.loop_closures), runtime::InputKind::kLoopClosures);
  const std::string truth_channel = "GROUND_TRUTH";

  const bool keep_all = options.max_kept == 0;
  runtime::Publisher publisher(cfg.channels, cfg.name, result.primary_estimator,
                               [&](const std::string& channel, const std::vector<uint8_t>& bytes, int64_t utime) {
                                 if (options.on_publish) options.on_publish(channel, bytes, utime);
                                 if (keep_all) result.published.push_back({channel, utime, bytes});
                               });
  std::map<std::string, EvenSample> fused_samples;
  EvenSample truth_sample(options.max_kept), target_truth_sample(options.max_kept);
  const engine::Emit emit = [&](engine::Output o) {
    // A solve's wall-clock time differs from run to run; replay's outputs must not (the stage latencies of the
    // report keep the timing).
    if (auto* t = std::get_if<engine::Trajectory>(&o)) t->solve_ms = 0;
    if (options.on_output) options.on_output(o);
    std::visit(
        [&](const auto& x) {
          using T = std::decay_t<decltype(x)>;
          if constexpr (std::is_same_v<T, engine::FusedPose>) {
            ++result.fused_pose_counts[x.estimator];
            result.last_fused_poses[x.estimator] = x;
            if (options.on_fused_pose) options.on_fused_pose(x);
            fused_samples.try_emplace(x.estimator, options.max_kept).first->second.push(result.fused_poses[x.estimator], x);
          } else if constexpr (std::is_same_v<T, engine::Trajectory>) {
            ++result.trajectory_messages;
            if (keep_all) result.trajectories.push_back(x);
          } else if constexpr (std::is_same_v<T, engine::Targets>) {
            ++result.target_messages;
            result.targets.push_back(x);
            if (!keep_all && result.targets.size() > kNewestTargetsKept) result.targets.erase(result.targets.begin());
          } else {
            ++result.match_request_messages;
            if (keep_all) result.match_requests.push_back(x);
          }
        },
        o);
    publisher.publish(o);
  };

  std::vector<StageReport> stage_reports;
  std::vector<EvenSample> latency_samples;
  for (const auto& s : engine.stages()) {
    StageReport report;
    report.name = std::string(s->name());
    stage_reports.push_back(std::move(report));
    latency_samples.emplace_back(options.max_kept);
  }

  // Segments: per stretch of data time, each stage's processing times and the wall time.
  std::vector<std::vector<double>> segment_latency(stage_reports.size());
  auto segment_start_wall = std::chrono::steady_clock::now();
  int64_t segment_start_utime = 0;
  const auto segment_us = static_cast<int64_t>(options.segment_seconds * 1e6);
  auto close_segment = [&](int64_t end_utime) {
    SegmentReport seg;
    seg.start_s = static_cast<double>(segment_start_utime - result.first_utime) * 1e-6;
    seg.data_s = static_cast<double>(end_utime - segment_start_utime) * 1e-6;
    const auto now = std::chrono::steady_clock::now();
    seg.wall_s = std::chrono::duration<double>(now - segment_start_wall).count();
    seg.rss_kb = resident_kb();
    for (size_t i = 0; i < stage_reports.size(); ++i) {
      auto& l = segment_latency[i];
      std::sort(l.begin(), l.end());
      SegmentReport::Stage st;
      st.name = stage_reports[i].name;
      st.events = static_cast<int64_t>(l.size());
      if (!l.empty()) st.p50_ms = runtime::nearest_rank_percentile(l, 0.5), st.p99_ms = runtime::nearest_rank_percentile(l, 0.99), st.max_ms = l.back();
      seg.stages.push_back(st);
      l.clear();
      if (engine.stages()[i]->kind() == engine::StageKind::kGraph) seg.graph_counters = engine.stages()[i]->counters();
    }
    result.segments.push_back(std::move(seg));
    segment_start_wall = now;
    segment_start_utime = end_utime;
  };

  auto process = [&](const runtime::LogRecord& r) {
    if (r.channel == truth_channel) {
      sextant::truth_t t;
      if (runtime::decode_message(r.data, t)) {
        if (t.kind == "robot") {
          engine::Pose p;
          p.position = {t.position[0], t.position[1], t.position[2]};
          p.orientation = Eigen::Quaterniond(t.orientation[0], t.orientation[1], t.orientation[2], t.orientation[3]);
          truth_sample.push(result.truth_poses, TruthPose{t.utime, t.source, p});
        } else {
          TruthPoint point{t.utime, t.kind, t.id, {t.position[0], t.position[1], t.position[2]}};
          if (t.kind == "target") target_truth_sample.push(result.truth_points, std::move(point));  // moving: sampled
          else result.truth_points.push_back(std::move(point));
        }
      }
    } else if (auto event = intake.accept(r.channel, r.data.data(), r.data.size())) {
      const int64_t utime = engine::event_utime(*event);
      if (result.first_utime == 0) result.first_utime = segment_start_utime = utime;
      if (segment_us > 0 && utime >= segment_start_utime + segment_us) close_segment(segment_start_utime + segment_us);
      result.last_utime = std::max(result.last_utime, utime);
      auto& stages = engine.stages();
      for (size_t i = 0; i < stages.size(); ++i) {
        if (!stages[i]->accepts(*event)) continue;
        const auto t0 = std::chrono::steady_clock::now();
        if (auto failure = engine::handle_guarded(*stages[i], *event, emit)) {
          // As the daemon's stage thread: counted, and the stage recovered before the next event.
          StageReport& report = stage_reports[i];
          ++report.failures;
          report.recoveries += failure->recovered ? 1 : 0;
          report.last_failure = failure->recovered ? failure->message : failure->recover_message;
        }
        const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        latency_samples[i].push(stage_reports[i].latency_ms, ms);
        if (segment_us > 0) segment_latency[i].push_back(ms);
        stage_reports[i].latency_max_ms = std::max(stage_reports[i].latency_max_ms, ms);
        ++stage_reports[i].processed;
      }
    }
  };

  // Pass 2: the records in their turn; one read early waits (in memory) for its turn.
  {
    runtime::LogReader reader(log_path);
    std::map<uint32_t, runtime::LogRecord> early;
    uint32_t next_turn = 0, index = 0;
    int64_t done = 0;
    auto step = [&](const runtime::LogRecord& r) {
      process(r);
      ++next_turn;
      if (progress && (++done % 4096 == 0)) progress(done, result.records);
    };
    while (auto r = reader.next()) {
      if (index >= rank.size()) break;  // the file grew since pass 1
      const uint32_t turn = rank[index++];
      if (turn != next_turn) {
        early.emplace(turn, std::move(*r));
        continue;
      }
      step(*r);
      for (auto it = early.begin(); it != early.end() && it->first == next_turn; it = early.erase(it)) step(it->second);
    }
  }
  engine.finish(emit);
  if (segment_us > 0 && result.last_utime > segment_start_utime) close_segment(result.last_utime);
  if (progress) progress(result.records, result.records);

  for (size_t i = 0; i < stage_reports.size(); ++i) {
    StageReport& report = stage_reports[i];
    report.counters = engine.stages()[i]->counters();
    report.counters.push_back({"stage_failures", report.failures});  // named as on the daemon's status
    report.counters.push_back({"stage_recoveries", report.recoveries});
  }
  result.stages = std::move(stage_reports);
  result.channels = stats.snapshot();
  result.published_counts = publisher.counts();
  result.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return result;
}

}  // namespace sextant::replay
