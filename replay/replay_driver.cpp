#include "replay/replay_driver.hpp"

#include "daemon/engine/engine.hpp"
#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/engine_driver.hpp"
#include "daemon/runtime/lcm_log.hpp"
#include "daemon/runtime/nearest_rank_percentile.hpp"
#include "replay/even_sample.hpp"
#include "replay/time_ordered_log.hpp"

#include <sextant/truth_t.hpp>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <numeric>

namespace sextant::tools {

namespace {

/// Targets messages a bounded replay keeps (the newest): what the report plots (the last 20 scans) and a margin.
constexpr size_t kNewestTargetsKept = 64;
/// The channel of the simulator's and converters' ground truth (truth_t): read for the report, not an input.
const std::string kTruthChannel = "GROUND_TRUTH";

/// The process's resident set size in KB (VmRSS of /proc/self/status), 0 where unavailable.
int64_t resident_kb() {
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::atoll(line.c_str() + 6);
  return 0;
}

/// What a replay keeps of what it sees: outputs, ground truth, the stages' processing times, the segments.
class ReplayCollector {
 public:
  ReplayCollector(ReplayResult& result, const ReplayOptions& options, const engine::Engine& engine)
      : result_(result),
        options_(options),
        engine_(engine),
        keep_all_(options.max_kept == 0),
        truth_sample_(options.max_kept),
        target_truth_sample_(options.max_kept),
        segment_us_(static_cast<int64_t>(options.segment_seconds * 1e6)) {
    for (const auto& s : engine.stages()) {
      StageReport report;
      report.name = std::string(s->name());
      result_.stages.push_back(std::move(report));
      latency_samples_.emplace_back(options.max_kept);
      graph_stage_.push_back(s->kind() == engine::StageKind::kGraph);
    }
    segment_latency_.resize(result_.stages.size());
  }

  void published(const std::string& channel, const std::vector<uint8_t>& bytes, int64_t utime);
  void output(const engine::Output& o);
  void truth(const runtime::LogRecord& r);
  void handled(size_t stage, double ms);
  /// The driver whose stages close_segment reads (after settle()).
  void attach(runtime::EngineDriver& driver) { driver_ = &driver; }
  /// Before an event of `utime` goes to the stages: closes the segments it ends.
  void event_at(int64_t utime);
  void close_segment(int64_t end_utime);
  void finish(runtime::EngineDriver& driver);

 private:
  void fused_pose(const engine::FusedPose& x);

  ReplayResult& result_;
  runtime::EngineDriver* driver_ = nullptr;
  const ReplayOptions& options_;
  const engine::Engine& engine_;
  const bool keep_all_;
  std::map<std::string, EvenSample> fused_samples_;
  EvenSample truth_sample_, target_truth_sample_;
  std::vector<EvenSample> latency_samples_;
  std::vector<bool> graph_stage_;
  // Segments: per stretch of data time, each stage's processing times and the wall time.
  const int64_t segment_us_;
  std::vector<std::vector<double>> segment_latency_;
  std::chrono::steady_clock::time_point segment_start_wall_ = std::chrono::steady_clock::now();
  int64_t segment_start_utime_ = 0;
};

void ReplayCollector::published(const std::string& channel, const std::vector<uint8_t>& bytes, int64_t utime) {
  if (options_.on_publish) options_.on_publish(channel, bytes, utime);
  if (keep_all_) result_.published.push_back({channel, utime, bytes});
}

void ReplayCollector::fused_pose(const engine::FusedPose& x) {
  ++result_.fused_pose_counts[x.estimator];
  result_.last_fused_poses[x.estimator] = x;
  if (options_.on_fused_pose) options_.on_fused_pose(x);
  fused_samples_.try_emplace(x.estimator, options_.max_kept).first->second.push(result_.fused_poses[x.estimator], x);
}

void ReplayCollector::output(const engine::Output& o) {
  if (options_.on_output) options_.on_output(o);
  std::visit(
      [&](const auto& x) {
        using T = std::decay_t<decltype(x)>;
        if constexpr (std::is_same_v<T, engine::FusedPose>) {
          fused_pose(x);
        } else if constexpr (std::is_same_v<T, engine::GeoPose>) {
          ++result_.geo_pose_messages;
          result_.last_geo_poses[x.source + "/" + x.estimator] = x;
        } else if constexpr (std::is_same_v<T, engine::Trajectory>) {
          ++result_.trajectory_messages;
          if (keep_all_) result_.trajectories.push_back(x);
        } else if constexpr (std::is_same_v<T, engine::Targets>) {
          ++result_.target_messages;
          result_.targets.push_back(x);
          if (!keep_all_ && result_.targets.size() > kNewestTargetsKept) result_.targets.erase(result_.targets.begin());
        } else if constexpr (std::is_same_v<T, engine::LandmarkMap>) {
          ++result_.landmark_map_messages;
          if (keep_all_) result_.landmark_maps.push_back(x);
        } else if constexpr (std::is_same_v<T, engine::FleetContributions> || std::is_same_v<T, engine::FleetControl>) {
          ++result_.fleet_messages;
        } else {
          ++result_.match_request_messages;
          if (keep_all_) result_.match_requests.push_back(x);
        }
      },
      o);
}

void ReplayCollector::truth(const runtime::LogRecord& r) {
  sextant::truth_t t;
  if (!runtime::decode_message(r.data, t)) return;
  if (t.kind == "robot") {
    engine::Pose p;
    p.position = {t.position[0], t.position[1], t.position[2]};
    p.orientation = Eigen::Quaterniond(t.orientation[0], t.orientation[1], t.orientation[2], t.orientation[3]);
    truth_sample_.push(result_.truth_poses, TruthPose{t.utime, t.source, p});
    return;
  }
  TruthPoint point{t.utime, t.kind, t.id, {t.position[0], t.position[1], t.position[2]}};
  if (t.kind == "target")
    target_truth_sample_.push(result_.truth_points, std::move(point));  // moving: sampled
  else
    result_.truth_points.push_back(std::move(point));
}

void ReplayCollector::handled(size_t stage, double ms) {
  StageReport& report = result_.stages[stage];
  latency_samples_[stage].push(report.latency_ms, ms);
  if (segment_us_ > 0) segment_latency_[stage].push_back(ms);
  report.latency_max_ms = std::max(report.latency_max_ms, ms);
  ++report.processed;
}

void ReplayCollector::event_at(int64_t utime) {
  if (result_.first_utime == 0) result_.first_utime = segment_start_utime_ = utime;
  if (segment_us_ > 0 && utime >= segment_start_utime_ + segment_us_) close_segment(segment_start_utime_ + segment_us_);
  result_.last_utime = std::max(result_.last_utime, utime);
}

void ReplayCollector::close_segment(int64_t end_utime) {
  // Every event before is handled and its processing times are in (pipelined lanes deliver them a little later); the
  // stages are idle, so the graph's counters can be read.
  if (driver_) driver_->settle();
  SegmentReport seg;
  seg.start_s = static_cast<double>(segment_start_utime_ - result_.first_utime) * 1e-6;
  seg.data_s = static_cast<double>(end_utime - segment_start_utime_) * 1e-6;
  const auto now = std::chrono::steady_clock::now();
  seg.wall_s = std::chrono::duration<double>(now - segment_start_wall_).count();
  seg.rss_kb = resident_kb();
  for (size_t i = 0; i < result_.stages.size(); ++i) {
    auto& l = segment_latency_[i];
    std::sort(l.begin(), l.end());
    SegmentReport::Stage st;
    st.name = result_.stages[i].name;
    st.events = static_cast<int64_t>(l.size());
    if (!l.empty())
      st.p50_ms = runtime::nearest_rank_percentile(l, 0.5), st.p99_ms = runtime::nearest_rank_percentile(l, 0.99),
      st.max_ms = l.back();
    seg.stages.push_back(st);
    l.clear();
    if (graph_stage_[i]) seg.graph_counters = engine_.stages()[i]->counters();
  }
  result_.segments.push_back(std::move(seg));
  segment_start_wall_ = now;
  segment_start_utime_ = end_utime;
}

void ReplayCollector::finish(runtime::EngineDriver& driver) {
  if (segment_us_ > 0 && result_.last_utime > segment_start_utime_) close_segment(result_.last_utime);
  const auto status = driver.stage_status();
  for (size_t i = 0; i < result_.stages.size() && i < status.size(); ++i) {
    StageReport& report = result_.stages[i];
    report.counters = status[i].counters;
    report.last_failure = status[i].last_failure;
    for (const auto& [name, value] : report.counters) {
      if (name == "stage_failures") report.failures = value;
      if (name == "stage_recoveries") report.recoveries = value;
    }
  }
  result_.channels = driver.stats().snapshot();
  result_.published_counts = driver.publisher().counts();
}

}  // namespace

ReplayResult replay_log(const std::string& log_path, const config::DaemonConfig& cfg, const Progress& progress,
                        const ReplayOptions& options) {
  const auto wall_start = std::chrono::steady_clock::now();
  ReplayResult result;
  TimeOrderedLog log(log_path);
  result.log_damage = log.damage();
  result.records = static_cast<int64_t>(log.records());

  engine::Engine engine(cfg.engine);
  result.primary_estimator = engine.primary_estimator();
  ReplayCollector collector(result, options, engine);
  runtime::DriverOptions o;
  o.lanes = options.pipelined ? runtime::StageLanes::kPipelined : runtime::StageLanes::kInline;
  o.zero_solve_time = true;
  o.on_accepted = [&](const engine::Event& e) { collector.event_at(engine::event_utime(e)); };
  o.on_published = [&](const engine::Output& out) { collector.output(out); };
  o.on_handled = [&](size_t stage, double ms) { collector.handled(stage, ms); };
  runtime::EngineDriver driver(
      cfg, engine,
      [&](const std::string& channel, const std::vector<uint8_t>& bytes, int64_t utime) {
        collector.published(channel, bytes, utime);
      },
      std::move(o));
  collector.attach(driver);

  int64_t done = 0;
  log.for_each([&](const runtime::LogRecord& r) {
    if (r.channel == kTruthChannel) {
      collector.truth(r);
    } else {
      // The log's time is the clock: the intake's idle expiry goes by it, not by how fast the replay runs.
      const int64_t utime = replay_stamp(r);
      driver.input(r.channel, r.data.data(), r.data.size(), runtime::Arrival::at_log_time(utime));
    }
    if (progress && (++done % 4096 == 0)) progress(done, result.records);
  });
  driver.finish();
  collector.finish(driver);
  if (progress) progress(result.records, result.records);
  result.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return result;
}

}  // namespace sextant::tools
