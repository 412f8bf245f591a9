#include "replay/replay_driver.hpp"

#include "daemon/engine/engine.hpp"
#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/intake.hpp"
#include "daemon/runtime/lcm_log.hpp"
#include "daemon/runtime/publisher.hpp"

#include <sextant/truth_t.hpp>

#include <algorithm>
#include <chrono>
#include <numeric>

namespace sextant::replay {

std::optional<int64_t> peek_utime(const std::vector<uint8_t>& b) {
  if (b.size() < 16) return std::nullopt;
  uint64_t v = 0;
  for (int i = 8; i < 16; ++i) v = (v << 8) | b[static_cast<size_t>(i)];  // LCM encodes big-endian
  return static_cast<int64_t>(v);
}

ReplayResult replay_log(const std::string& log_path, const config::DaemonConfig& cfg, const Progress& progress) {
  const auto wall_start = std::chrono::steady_clock::now();
  runtime::LogDamage damage;
  std::vector<runtime::LogRecord> records = runtime::LogReader::read_all(log_path, &damage);

  ReplayResult result;
  result.log_damage = std::move(damage);
  result.records = static_cast<int64_t>(records.size());
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

  // Order: by message utime, ties in file order.  Records that are not ours (or too short to carry a utime) keep
  // their log stamp so that they still get counted.
  std::vector<size_t> order(records.size());
  std::vector<int64_t> keys(records.size());
  for (size_t i = 0; i < records.size(); ++i) keys[i] = peek_utime(records[i].data).value_or(records[i].timestamp);
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return keys[a] < keys[b]; });

  runtime::Publisher publisher(cfg.channels, cfg.name, result.primary_estimator,
                               [&result](const std::string& channel, const std::vector<uint8_t>& bytes, int64_t utime) {
                                 result.published.push_back({channel, utime, bytes});
                               });
  const engine::Emit emit = [&](engine::Output o) {
    // A solve's wall-clock time differs from run to run; replay's outputs must not (the stage latencies of the
    // report keep the timing).
    if (auto* t = std::get_if<engine::Trajectory>(&o)) t->solve_ms = 0;
    std::visit(
        [&](const auto& x) {
          using T = std::decay_t<decltype(x)>;
          if constexpr (std::is_same_v<T, engine::FusedPose>) result.fused_poses[x.estimator].push_back(x);
          else if constexpr (std::is_same_v<T, engine::Trajectory>) result.trajectories.push_back(x);
          else if constexpr (std::is_same_v<T, engine::Targets>) result.targets.push_back(x);
          else result.match_requests.push_back(x);
        },
        o);
    publisher.publish(o);
  };

  std::vector<StageReport> stage_reports;
  for (const auto& s : engine.stages()) stage_reports.push_back({std::string(s->name()), 0, {}, {}});

  int64_t done = 0;
  for (size_t idx : order) {
    const auto& r = records[idx];
    if (r.channel == truth_channel) {
      sextant::truth_t t;
      if (runtime::decode_message(r.data, t)) {
        if (t.kind == "robot") {
          engine::Pose p;
          p.position = {t.position[0], t.position[1], t.position[2]};
          p.orientation = Eigen::Quaterniond(t.orientation[0], t.orientation[1], t.orientation[2], t.orientation[3]);
          result.truth_poses.push_back({t.utime, t.source, p});
        } else {
          result.truth_points.push_back({t.utime, t.kind, t.id, {t.position[0], t.position[1], t.position[2]}});
        }
      }
    } else if (auto event = intake.accept(r.channel, r.data.data(), r.data.size())) {
      const int64_t utime = engine::event_utime(*event);
      if (result.first_utime == 0) result.first_utime = utime;
      result.last_utime = std::max(result.last_utime, utime);
      auto& stages = engine.stages();
      for (size_t i = 0; i < stages.size(); ++i) {
        if (!stages[i]->accepts(*event)) continue;
        const auto t0 = std::chrono::steady_clock::now();
        stages[i]->handle(*event, emit);
        stage_reports[i].latency_ms.push_back(
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
        ++stage_reports[i].processed;
      }
    }
    if (progress && (++done % 4096 == 0)) progress(done, result.records);
  }
  engine.finish(emit);
  if (progress) progress(result.records, result.records);

  for (size_t i = 0; i < stage_reports.size(); ++i) stage_reports[i].counters = engine.stages()[i]->counters();
  result.stages = std::move(stage_reports);
  result.channels = stats.snapshot();
  result.published_counts = publisher.counts();
  result.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return result;
}

}  // namespace sextant::replay
