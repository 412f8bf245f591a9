#include "daemon/config/stage_config_readers.hpp"

#include <cmath>
#include <cstdlib>
#include <limits>
#include <optional>
#include <string>

namespace sextant::config {
namespace {

void read_keyframes(Section& s, engine::GraphConfig& c) {
  Section k = s.child("keyframes");
  k.get("k1", c.keyframes.k1, non_negative());
  k.get("k2", c.keyframes.k2, positive());
  k.get("translation_weight", c.keyframes.translation_weight, non_negative());
  k.get("rotation_weight", c.keyframes.rotation_weight, non_negative());
  k.get("reanchor_after", c.keyframes.reanchor_after, int_in_range(0, 1 << 20));
  if (!(c.keyframes.k1 < c.keyframes.k2)) throw k.error("'" + k.path() + "': k1 must be smaller than k2");
  if (c.keyframes.translation_weight == 0 && c.keyframes.rotation_weight == 0)
    throw k.error("'" + k.path() + "': translation_weight and rotation_weight cannot both be 0");
  k.reject_unknown_keys();
}

void read_loops(Section& s, engine::GraphConfig& c) {
  Section p = s.child("loops");
  p.get("propose", c.propose_loops);
  p.get("max_waiting", c.max_waiting_loops, int_in_range(0, 1 << 20));
  p.get("n1", c.proposals.n1, int_in_range(0, 1000));
  p.get("n2", c.proposals.n2, int_in_range(-1, 1000));
  int seed = static_cast<int>(c.proposals.seed);
  p.get("seed", seed, int_in_range(0, 2147483647));
  c.proposals.seed = static_cast<uint64_t>(seed);
  p.get_parsed("robust", c.robust, graph::robust_kernel_from_name);
  // "auto" (a chi-square quantile of the loops' dimension, kernel_width_for in estimators/slam/slam_options.hpp) or a
  // number.
  std::string width;  // stays empty when the key is absent (the default stays)
  p.get("kernel_width", width, Check<std::string>([](const std::string& v) -> std::optional<std::string> {
          if (v == "auto") return std::nullopt;
          char* end = nullptr;
          const double x = std::strtod(v.c_str(), &end);
          if (end == v.c_str() || *end != '\0' || !std::isfinite(x) || !(x > 0))
            return "expected 'auto' or a positive number, got '" + v + "'";
          return std::nullopt;
        }));
  if (width == "auto")
    c.kernel_width.reset();
  else if (!width.empty())
    c.kernel_width = std::strtod(width.c_str(), nullptr);
  p.get("gate_probability", c.loop_gate_probability, in_range(0.5, 0.999999999));
  p.get("gate_odometry_scale", c.loop_gate_odometry_scale, positive());
  p.get("max_landing_sigma", c.loop_max_landing_sigma, positive());
  p.get("time_tolerance_s", c.loop_time_tolerance_s, non_negative());
  p.reject_unknown_keys();
}

void read_landmarks(Section& s, engine::GraphConfig& c) {
  Section l = s.child("landmarks");
  l.get("enabled", c.landmarks.enabled);
  l.get("robust", c.landmarks.robust);
  l.get("gate_probability", c.landmarks.gate_probability, in_range(0.5, 0.999999999));
  l.get("gate_odometry_scale", c.landmarks.gate_odometry_scale, positive());
  l.get("max_waiting", c.landmarks.max_waiting, int_in_range(0, 1 << 20));
  l.reject_unknown_keys();
}

// A body name as the messages' `source` carries it: not empty, at most 256 characters (codec.cpp's rule).
Check<std::string> body_name() {
  return [](const std::string& v) -> std::optional<std::string> {
    if (v.empty() || v.size() > 256) return "a body name of 1 to 256 characters";
    return std::nullopt;
  };
}

// A daemon's name as daemon.name takes it: 1 to 64 characters, no control characters.
std::optional<std::string> daemon_name_error(const std::string& v) {
  if (v.empty() || v.size() > 64) return "a daemon name of 1 to 64 characters, got '" + v + "'";
  for (unsigned char ch : v)
    if (ch < 0x20 || ch == 0x7f) return "a daemon name without control characters";
  return std::nullopt;
}

// fleet.exchange: several daemons, one per robot, exchanging graph contributions (daemon/engine/fleet_exchange.hpp).
// Whether daemon.name is among the members is checked where both are known (daemon_config.cpp).
void read_exchange(Section& f, engine::GraphConfig& c) {
  Section x = f.child("exchange");
  engine::FleetExchangeOptions& o = c.fleet_exchange;
  x.get("enabled", o.enabled);
  x.get("members", o.members,
        Check<std::vector<std::string>>([](const std::vector<std::string>& v) -> std::optional<std::string> {
          if (v.size() > 256) return "at most 256 members";
          for (size_t i = 0; i < v.size(); ++i) {
            if (auto why = daemon_name_error(v[i])) return why;
            for (size_t j = 0; j < i; ++j)
              if (v[i] == v[j]) return "'" + v[i] + "' is listed twice";
          }
          return std::nullopt;
        }));
  x.get("retain", o.retain, int_in_range(1, 1 << 24));
  x.get("retain_mb", o.retain_mb, int_in_range(1, 1 << 16));
  x.get("heartbeat_period_s", o.heartbeat_period_s, in_range(0.01, 3600));
  x.get("repair_backoff_s", o.repair_backoff_s, in_range(0.001, 3600));
  x.get("repair_backoff_max_s", o.repair_backoff_max_s, in_range(0.001, 3600));
  x.get("max_streams_per_sender", o.max_streams_per_sender, int_in_range(1, 1 << 16));
  x.get("reorder_window", o.reorder_window, int_in_range(1, 1 << 20));
  x.get("reorder_mb", o.reorder_mb, int_in_range(1, 1 << 16));
  x.get("max_repair_range", o.max_repair_range, int_in_range(1, 1 << 20));
  x.get("repair_bytes_per_s", o.repair_bytes_per_s, in_range(1000, 1e9));
  // The largest item (256 sightings, two names of 256 characters) and its message's fields must fit.
  x.get("max_message_bytes", o.max_message_bytes, int_in_range(32768, 65000));
  x.get("restart_wait_s", o.restart_wait_s, in_range(0.01, 3600));
  if (o.repair_backoff_max_s < o.repair_backoff_s)
    throw x.error("'" + x.path() + "': repair_backoff_max_s must not be smaller than repair_backoff_s");
  if (o.enabled && o.members.empty())
    throw x.error("'" + x.path() + "': enabled without members (the fleet's daemon names)");
  if (o.enabled && !c.fleet.enabled)
    throw x.error("'" + x.path() + "': enabled while '" + f.path() + ".enabled' is false");
  x.reject_unknown_keys();
}

// fleet: {enabled, markers: {ID: BODY}, placement: {...}, max_pending, join_every_keyframes,
// exchange: {...}}
void read_fleet(Section& s, engine::GraphConfig& c) {
  Section f = s.child("fleet");
  slam::FleetOptions& o = c.fleet;
  f.get("enabled", o.enabled);
  f.get("max_pending", o.max_pending, int_in_range(1, 1 << 16));
  f.get("join_every_keyframes", o.join_every_keyframes, int_in_range(1, 1 << 20));
  f.get("proposal_radius", o.proposal_radius, non_negative());
  Section markers = f.child("markers");
  if (markers.node().IsDefined() && !markers.node().IsNull()) {
    if (!markers.node().IsMap()) throw markers.error("'" + markers.path() + "': expected a map of landmark id -> body");
    for (const YAML::Node& key : markers.keys()) {
      int64_t id = -1;
      if (!YAML::convert<int64_t>::decode(key, id) || id < 0)
        throw markers.error_at(
            key, "'" + markers.path() + "': a marker id must be a non-negative integer, not '" + key.Scalar() + "'");
      std::string body;
      markers.get(key.Scalar(), body, body_name());
      o.markers[id] = body;
    }
  }
  Section p = f.child("placement");
  p.get("min_support", o.placement.min_support, int_in_range(2, 1000));
  p.get("min_inlier_ratio", o.placement.min_inlier_ratio, in_range(0.0, 1.0));
  p.get("inlier_distance", o.placement.inlier_distance, positive());
  p.get("inlier_angle", o.placement.inlier_angle, in_range(1e-6, 3.14159));
  p.get("min_spread", o.placement.min_spread, non_negative());
  p.get("min_pair_distance", o.placement.min_pair_distance, positive());
  p.get("rival_ratio", o.placement.rival_ratio, in_range(0.0, 1.0));
  p.get("max_evidence", o.placement.max_evidence, int_in_range(2, 256));
  p.reject_unknown_keys();
  read_exchange(f, c);
  // Daemons that exchange contributions keep every frame's gauge on its root's first keyframe, the same on each
  // (slam_options.hpp, LifelongOptions::hold_frame).
  if (c.fleet_exchange.enabled) c.lifelong.hold_frame = false;
  f.reject_unknown_keys();
}

void read_smoother(Section& s, engine::GraphConfig& c) {
  // The incremental smoother's options (estimators/graph/incremental_options.hpp says what each does); an absent
  // key keeps IncrementalOptions' default.
  Section m = s.child("smoother");
  graph::IncrementalOptions& o = c.smoother;
  m.get("relinearize_translation", o.relinearize_translation, positive());
  m.get("relinearize_rotation", o.relinearize_rotation, positive());
  m.get("relinearization_passes", o.relinearization_passes, int_in_range(0, 100));
  m.get("relinearize_skip", o.relinearize_skip, int_in_range(1, 1 << 20));
  m.get("wildfire", o.wildfire, non_negative());
  m.get("update_fraction", o.update_fraction, in_range(0.0, 1.0));
  m.get("min_update_factors", o.min_update_factors, int_in_range(1, 1 << 20));
  m.get("max_update_factors", o.max_update_factors, int_in_range(1, 1 << 20));
  m.get("relinearize_work", o.relinearize_work, positive());
  m.get("heavy_relinearize_every", o.heavy_relinearize_every, int_in_range(1, 1 << 20));
  m.get("rebuild_iterations", o.rebuild_iterations, int_in_range(1, 1 << 20));
  m.get("refill_ratio", o.refill_ratio, Check<double>([](const double& v) -> std::optional<std::string> {
          if (v > 1 && std::isfinite(v)) return std::nullopt;  // at 1 any fill-in would reorder at every update
          return "must be a number > 1, got " + std::to_string(v);
        }));
  m.get("nested_dissection_above", o.nested_dissection_above, int_in_range(0, std::numeric_limits<int>::max()));
  m.get("reorder_spread", o.reorder_spread, int_in_range(0, 1000));
  m.get("reorder_spread_above", o.reorder_spread_above, int_in_range(0, std::numeric_limits<int>::max()));
  m.get("reorder_spread_nonzeros", o.reorder_spread_nonzeros, int_in_range(0, std::numeric_limits<int>::max()));
  m.get("reorder_spread_factors", o.reorder_spread_factors, int_in_range(0, std::numeric_limits<int>::max()));
  m.get("reorder_slice_ms", o.reorder_slice_ms, non_negative());
  if (o.max_update_factors < o.min_update_factors) {
    // The smoother would quietly take the larger; name the key that was set.
    const YAML::Node& n = m.node();
    const YAML::Node at = n.IsMap() && n["max_update_factors"] ? n["max_update_factors"]
                          : n.IsMap()                          ? n["min_update_factors"]
                                                               : n;
    throw m.error_at(at, "'" + m.path() + "': max_update_factors (" + std::to_string(o.max_update_factors) +
                             ") must not be smaller than min_update_factors (" + std::to_string(o.min_update_factors) +
                             ")");
  }
  m.reject_unknown_keys();
}

// Keys that moved or are gone: say where they went.
void reject_moved_smoother_keys(Section& s) {
  // The relinearization thresholds were keys of this section in earlier versions.
  if (s.node().IsMap())
    for (const YAML::Node& key : s.keys())
      for (const char* moved : {"relinearize_translation", "relinearize_rotation"})
        if (key.Scalar() == moved)
          throw s.error_at(key,
                           "'" + s.path() + "." + moved + "' has moved to '" + s.path() + ".smoother." + moved + "'");
}

void reject_gone_trajectory_key(Section& s) {
  if (s.node().IsMap() && s.node()["trajectory_max_keyframes"])
    throw s.error_at(s.node()["trajectory_max_keyframes"],
                     "'" + s.path() +
                         ".trajectory_max_keyframes' is gone: TRAJECTORY now sends new and moved keyframes and a "
                         "rolling snapshot in bounded messages (see '" +
                         s.path() + ".trajectory')");
}

// The odometry's keys: regularization, history, batching.
void read_odometry(Section& s, engine::GraphConfig& c) {
  s.get("min_increment_variance", c.min_increment_variance, positive());
  s.get("odometry_history", c.odometry_history, int_in_range(1, 100000000));
  s.get("coalesce_odometry", c.coalesce_odometry);
  s.get("odometry_batch_max", c.odometry_batch_max, int_in_range(1, 1 << 20));
  s.get("odometry_waiting_max", c.odometry_waiting_max, int_in_range(1, 1 << 24));
  s.get("odometry_waiting_total_max", c.odometry_waiting_total_max, int_in_range(1, 1 << 24));
}

void read_lifelong(Section& s, engine::GraphConfig& c) {
  Section l = s.child("lifelong");
  l.get("enabled", c.lifelong.enabled);
  for (const char* gone : {"max_keyframes", "window"})
    if (l.node().IsMap() && l.node()[gone])
      throw l.error_at(l.node()[gone], "'" + l.path() + "." + gone + "' is now per kind of body: '" + l.path() +
                                           ".planar." + gone + "' and '" + l.path() + ".spatial." + gone + "'");
  l.get("cell_size", c.lifelong.thinning.cell_size, positive());
  l.get("heading_sector", c.lifelong.thinning.heading_sector, in_range(1e-3, 2 * M_PI));
  for (auto [key, budget] : {std::pair{"planar", &c.lifelong.planar}, std::pair{"spatial", &c.lifelong.spatial}}) {
    Section b = l.child(key);
    b.get("max_keyframes", budget->max_keyframes, int_in_range(2, 1 << 24));
    b.get("window", budget->window, int_in_range(1, 1 << 24));
    b.reject_unknown_keys();
  }
  l.reject_unknown_keys();
}

void read_trajectory(Section& s, engine::GraphConfig& c) {
  Section t = s.child("trajectory");
  engine::TrajectoryFeedOptions& o = c.trajectory;
  t.get("rate_hz", o.rate_hz, non_negative());
  t.get("move_translation", o.move_translation, positive());
  t.get("move_rotation", o.move_rotation, positive());
  t.get("max_keyframes_per_message", o.max_keyframes_per_message, int_in_range(1, 850));  // 850 x 72 B < 64 KB
  t.get("max_keyframes_per_tick", o.max_keyframes_per_tick, int_in_range(1, 1 << 20));
  t.get("snapshot_chunk", o.snapshot_chunk, int_in_range(0, 850));
  t.reject_unknown_keys();
}

}  // namespace

void read_stage_config(Section& s, engine::GraphConfig& c) {
  s.get("enabled", c.enabled);
  s.get("solve_period_s", c.solve_period_s, in_range(0.0, 10.0));
  read_keyframes(s, c);
  read_loops(s, c);
  read_landmarks(s, c);
  read_fleet(s, c);
  read_smoother(s, c);
  reject_moved_smoother_keys(s);
  read_odometry(s, c);
  reject_gone_trajectory_key(s);
  read_lifelong(s, c);
  read_trajectory(s, c);
  s.reject_unknown_keys();
}

}  // namespace sextant::config
