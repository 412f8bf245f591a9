// daemon_latency: sextantd's latency from an odometry message in to its FUSED_POSE out, over LCM, while the graph
// back end works through a pose graph in the background — next to the raw LCM round trip measured in the same run.
// bench/latency/run.sh runs it all in a private network namespace.
//
//   daemon_latency echo [--lcm-url URL] [--ping CH] [--pong CH]
//       The trivial peer of the raw round trip: republishes every message of CH, byte for byte, on PONG, until
//       SIGINT/SIGTERM.
//   daemon_latency measure (--feed GRAPH.lcm | --idle) [--duration S] [--rate HZ] [--window N] [--feed-rate HZ]
//                          [--json FILE] [--samples FILE]
//       Four threads, one LCM instance each:
//       - sender: odometry of one body (odometry_track.hpp) on ODOMETRY at --rate, and the same bytes on the ping
//         channel half a period later; utime k <-> send time k (steady clock, taken just before lcm_publish);
//       - receiver: every FUSED_POSE* message of that body and every pong, stamped on arrival in the handler,
//         paired by utime with its send time;
//       - feeder: republishes a log of ODOMETRY + LOOP_CLOSURES of a second body (`sextant convert g2o` output: one
//         odometry message per vertex, each loop right after the odometry of its later vertex) with flow control:
//         at most --window poses ahead of the newest keyframe on the daemon's TRAJECTORY, at most --feed-rate poses
//         per second — so the optimizer always has work queued without a growing backlog of the fed body (the
//         measured body's odometry still goes through the graph stage's queue: drops there are reported);
//       - monitor: TRAJECTORY of the fed body (solve_ms, keyframe ids) and SEXTANT_STATUS (the graph stage's counters,
//         queue depth, drops).
//       --idle: no feeder (the baseline: the same measurement with the optimizer idle but for the measured body's own
//       keyframes).
//       --inertial: the sender publishes the body's IMU at --rate instead (inertial_track.hpp), its odometry with the
//       twist every --odometry-every samples and a GNSS fix every --gnss-every; a fused pose is expected (and timed
//       from the IMU sample of its utime) at the odometry's times only.
//       Reports p50 / p99 / max of each latency (nearest rank), samples and lost messages per channel, and the
//       optimizer's progress during the measurement.  Exit 1 when no fused pose of the body arrives on an expected
//       channel, when no pong arrives, or when the optimizer did not run during the measurement; 3 when LCM
//       cannot start.
#include "bench/latency/inertial_track.hpp"
#include "bench/latency/odometry_track.hpp"
#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/latency_recorder.hpp"
#include "daemon/runtime/lcm_log.hpp"
#include "daemon/runtime/raw_subscription.hpp"
#include "report/json_writer.hpp"

#include <sextant/status_t.hpp>

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <map>
#include <mutex>
#include <thread>

namespace {

using Clock = std::chrono::steady_clock;
using sextant::runtime::LatencyRecorder;
using sextant::runtime::LatencySummary;

std::atomic<bool> g_interrupted{false};

int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch()).count();
}

void handle_until(lcm::LCM& lcm, const std::atomic<bool>& stop) {
  while (!stop.load()) lcm.handleTimeout(20);
}

// ---------------------------------------------------------------------------------------------------------------
// echo

struct Echo {
  lcm::LCM& lcm;
  std::string pong;
  int64_t echoed = 0;
  void on_message(const lcm_recv_buf_t& b, const std::string&) {
    lcm.publish(pong, b.data, b.data_size);
    ++echoed;
  }
};

int run_echo(const std::string& url, const std::string& ping, const std::string& pong) {
  lcm::LCM lcm(url);
  if (!lcm.good()) {
    std::fprintf(stderr, "daemon_latency echo: cannot start LCM (no multicast route? see bench/latency/run.sh)\n");
    return 3;
  }
  Echo echo{lcm, pong};
  lcm_subscription_set_queue_capacity(sextant::runtime::subscribe_raw(lcm, ping, &echo), 100000);
  std::signal(SIGINT, [](int) { g_interrupted = true; });
  std::signal(SIGTERM, [](int) { g_interrupted = true; });
  handle_until(lcm, g_interrupted);
  std::fprintf(stderr, "daemon_latency echo: %lld messages echoed\n", static_cast<long long>(echo.echoed));
  return 0;
}

// ---------------------------------------------------------------------------------------------------------------
// measure

/// Arrival times (steady ns) of the replies to message k, per channel; -1 = not (yet) received.
struct Receiver {
  std::string source, pong;
  int64_t start_utime = 0, period_us = 1000;
  size_t count = 0;
  std::map<std::string, std::vector<int64_t>> arrivals;
  std::map<std::string, std::string> estimator;  // channel -> fused_pose_t.estimator
  int64_t duplicates = 0, undecodable = 0, unknown_time = 0;

  void on_message(const lcm_recv_buf_t& b, const std::string& channel) {
    const int64_t t = now_ns();
    int64_t utime = 0;
    if (channel == pong) {
      sextant::odometry_t m;
      if (m.decode(b.data, 0, static_cast<int>(b.data_size)) < 0) return void(++undecodable);
      utime = m.utime;
    } else {
      sextant::fused_pose_t m;
      if (m.decode(b.data, 0, static_cast<int>(b.data_size)) < 0) return void(++undecodable);
      if (m.source != source) return;  // the fed body's poses
      utime = m.utime;
      estimator.try_emplace(channel, m.estimator);
    }
    const int64_t k = (utime - start_utime) / period_us;
    if (utime < start_utime || (utime - start_utime) % period_us != 0 || k >= static_cast<int64_t>(count))
      return void(++unknown_time);
    auto& v = arrivals.try_emplace(channel, count, int64_t{-1}).first->second;
    if (v[static_cast<size_t>(k)] >= 0) return void(++duplicates);
    v[static_cast<size_t>(k)] = t;
  }
};

/// TRAJECTORY and SEXTANT_STATUS: the optimizer's progress.
struct Monitor {
  std::string fed_source, trajectory_channel, status_channel;
  std::atomic<int64_t> newest_keyframe{-1};  // of the fed body, as last published on TRAJECTORY

  struct Solve {
    int64_t at_ns;
    std::string source;
    double solve_ms;
    int64_t newest_keyframe;
    double chi2;
  };
  struct Status {
    int64_t at_ns;
    std::map<std::string, std::map<std::string, int64_t>> counters;  // stage -> counters (+ processed/dropped/queue)
    std::map<std::string, std::array<double, 3>> latency_ms;         // stage -> p50, p99, max (event in -> processed)
  };
  std::mutex mutex;
  std::vector<Solve> solves;
  std::map<std::string, int64_t> last_update_utime;  // per source: the publication the last solve was taken from
  std::vector<Status> statuses;

  void on_message(const lcm_recv_buf_t& b, const std::string& channel) {
    const int64_t t = now_ns();
    if (channel == trajectory_channel) {
      sextant::trajectory_t m;
      if (m.decode(b.data, 0, static_cast<int>(b.data_size)) < 0) return;
      // Keyframe ids only grow.  Neither kind of message ends with the newest: an UPDATE lists the new keyframes
      // first, then the moved ones; a SNAPSHOT chunk covers an older id range.  So the newest is the largest id seen.
      int64_t newest = -1;
      for (const auto& k : m.keyframes) newest = std::max(newest, k.id);
      if (m.source == fed_source) {
        int64_t seen = newest_keyframe.load();
        while (newest > seen && !newest_keyframe.compare_exchange_weak(seen, newest)) {}
        newest = std::max(newest, seen);
      }
      // One solve per publication: its UPDATE messages share the newest keyframe's time; SNAPSHOT chunks repeat
      // poses already solved.
      if (m.kind != sextant::trajectory_t::UPDATE) return;
      std::lock_guard lock(mutex);
      const auto last = last_update_utime.find(m.source);
      if (last != last_update_utime.end() && last->second == m.utime) return;
      last_update_utime[m.source] = m.utime;
      solves.push_back({t, m.source, m.solve_ms, newest, m.chi2});
    } else if (channel == status_channel) {
      sextant::status_t m;
      if (m.decode(b.data, 0, static_cast<int>(b.data_size)) < 0) return;
      Status s{t, {}, {}};
      for (const auto& st : m.stages) {
        auto& c = s.counters[st.name];
        for (int i = 0; i < st.num_counters; ++i)
          c[st.counter_names[static_cast<size_t>(i)]] = st.counter_values[static_cast<size_t>(i)];
        c["processed"] = st.processed;
        c["dropped"] = st.dropped;
        c["queue_depth"] = st.queue_depth;
        s.latency_ms[st.name] = {st.latency_ms_p50, st.latency_ms_p99, st.latency_ms_max};
      }
      std::lock_guard lock(mutex);
      statuses.push_back(std::move(s));
    }
  }
};

struct FeedOptions {
  std::string path;
  int64_t window = 4;      // poses ahead of the newest optimized keyframe
  double max_rate = 1000;  // poses per second
};

struct FeedResult {
  int64_t odometry = 0, loop_closures = 0, total_odometry = 0;
  int64_t finished_ns = -1;  // when the whole log was sent
};

/// Republishes the log's ODOMETRY / LOOP_CLOSURES in file order under flow control (see the file's header).
void feed(lcm::LCM& lcm, const std::vector<sextant::runtime::LogRecord>& log, const FeedOptions& o, Monitor& monitor,
          const std::atomic<bool>& stop, FeedResult& result) {
  for (const auto& r : log) result.total_odometry += r.channel == "ODOMETRY" ? 1 : 0;
  const auto start = Clock::now();
  const auto period = std::chrono::duration<double>(1.0 / o.max_rate);
  for (const auto& r : log) {
    if (r.channel == "ODOMETRY") {
      const int64_t k = result.odometry;  // the vertex index = the keyframe id (every pose becomes a keyframe)
      std::this_thread::sleep_until(start +
                                    std::chrono::duration_cast<Clock::duration>(period * static_cast<double>(k)));
      while (!stop.load() && k - monitor.newest_keyframe.load() > o.window)
        std::this_thread::sleep_for(std::chrono::microseconds(200));
      if (stop.load()) return;
      lcm.publish(r.channel, r.data.data(), static_cast<unsigned>(r.data.size()));
      ++result.odometry;
    } else if (r.channel == "LOOP_CLOSURES") {
      lcm.publish(r.channel, r.data.data(), static_cast<unsigned>(r.data.size()));
      ++result.loop_closures;
    }
  }
  result.finished_ns = now_ns();
}

struct ChannelResult {
  std::string channel, label;
  int64_t received = 0, lost = 0;
  LatencySummary latency;
};

/// The latencies of the replies to the messages sent; one reply is expected per `every` messages (an estimator
/// publishing at a fraction of the input's rate, in its own phase), the shortfall counted as lost.
ChannelResult summarize(const std::string& channel, const std::string& label, const std::vector<int64_t>& arrivals,
                        const std::vector<int64_t>& sent, size_t sent_count, size_t every = 1) {
  ChannelResult r;
  r.channel = channel;
  r.label = label;
  LatencyRecorder rec(std::max<size_t>(1, sent_count));
  for (size_t k = 0; k < sent_count && !arrivals.empty(); ++k) {
    if (arrivals[k] < 0) continue;
    ++r.received;
    rec.add(static_cast<double>(arrivals[k] - sent[k]) * 1e-6);
  }
  r.lost = std::max<int64_t>(0, static_cast<int64_t>((sent_count + every - 1) / every) - r.received);
  r.latency = rec.summary();
  return r;
}

struct MeasureOptions {
  std::string url;
  std::string odometry_channel = "ODOMETRY", fused_prefix = "FUSED_POSE", trajectory = "TRAJECTORY",
              status = "SEXTANT_STATUS", ping = "LATENCY_PING", pong = "LATENCY_PONG";
  std::vector<std::string> expect = {"FUSED_POSE", "FUSED_POSE_GRAPH"};
  std::string source = "latency_body", fed_source = "robot1";
  double duration_s = 60, rate_hz = 1000, warmup_s = 2, settle_s = 1.5;
  FeedOptions feed;
  bool idle = false;
  // The inertial mode (InertialTrack): IMU at --rate, odometry with its twist every odometry_every samples, a GNSS
  // fix every gnss_every; fused poses are expected at the odometry's times only.
  bool inertial = false;
  int64_t odometry_every = 20, gnss_every = 200;
  std::string imu_channel = "IMU", gnss_channel = "GNSS";
  std::string json, samples;
};

template <class Msg>
std::vector<uint8_t> encoded(const Msg& m) {
  std::vector<uint8_t> bytes(static_cast<size_t>(m.getEncodedSize()));
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

/// What the sender publishes at one step, in order, and the bytes it pings the echo with (the odometry message).
struct Step {
  std::vector<std::pair<const std::string*, std::vector<uint8_t>>> messages;
  std::vector<uint8_t> ping;
};

Step next_step(const MeasureOptions& o, sextant::bench::OdometryTrack& track,
               std::optional<sextant::bench::InertialTrack>& inertial, int64_t seq) {
  using sextant::runtime::to_message;
  Step s;
  if (!inertial) {
    s.ping = encoded(to_message(track.next(), "daemon_latency", seq));
    s.messages.push_back({&o.odometry_channel, s.ping});
    return s;
  }
  const sextant::bench::InertialSensors x = inertial->next();
  s.ping = encoded(to_message(x.odometry, "daemon_latency", seq));
  s.messages.push_back({&o.imu_channel, encoded(to_message(x.imu, "daemon_latency", seq))});
  if (x.publish_odometry) s.messages.push_back({&o.odometry_channel, s.ping});
  if (x.fix) s.messages.push_back({&o.gnss_channel, encoded(to_message(*x.fix, "daemon_latency", seq))});
  return s;
}

/// The 1-minute load average (/proc/loadavg; -1 where there is none).
double load_average() {
  double load = -1;
  std::ifstream("/proc/loadavg") >> load;
  return load;
}

const Monitor::Status* status_at(const std::vector<Monitor::Status>& all, int64_t t) {
  const Monitor::Status* best = nullptr;
  for (const auto& s : all)
    if (s.at_ns <= t) best = &s;
  return best;
}

int64_t counter(const Monitor::Status* s, const std::string& stage, const std::string& name) {
  if (s == nullptr) return 0;
  auto st = s->counters.find(stage);
  if (st == s->counters.end()) return 0;
  auto c = st->second.find(name);
  return c == st->second.end() ? 0 : c->second;
}

int run_measure(const MeasureOptions& o) {
  lcm::LCM rx_lcm(o.url), mon_lcm(o.url), tx_lcm(o.url), feed_lcm(o.url);
  if (!rx_lcm.good() || !mon_lcm.good() || !tx_lcm.good() || !feed_lcm.good()) {
    std::fprintf(stderr, "daemon_latency: cannot start LCM (no multicast route? see bench/latency/run.sh)\n");
    return 3;
  }
  std::vector<sextant::runtime::LogRecord> log;
  try {
    if (!o.idle) log = sextant::runtime::LogReader::read_all(o.feed.path);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "daemon_latency: --feed: %s\n", e.what());
    return 2;
  }

  const auto count = static_cast<size_t>(o.duration_s * o.rate_hz);
  const auto period_us = static_cast<int64_t>(std::llround(1e6 / o.rate_hz));
  const int64_t start_utime =
      std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
          .count();

  Receiver receiver;
  receiver.source = o.source;
  receiver.pong = o.pong;
  receiver.start_utime = start_utime;
  receiver.period_us = period_us;
  receiver.count = count;
  lcm_subscription_set_queue_capacity(sextant::runtime::subscribe_raw(rx_lcm, o.fused_prefix + ".*", &receiver),
                                      100000);
  lcm_subscription_set_queue_capacity(sextant::runtime::subscribe_raw(rx_lcm, o.pong, &receiver), 100000);
  Monitor monitor;
  monitor.fed_source = o.fed_source;
  monitor.trajectory_channel = o.trajectory;
  monitor.status_channel = o.status;
  lcm_subscription_set_queue_capacity(sextant::runtime::subscribe_raw(mon_lcm, o.trajectory, &monitor), 100000);
  lcm_subscription_set_queue_capacity(sextant::runtime::subscribe_raw(mon_lcm, o.status, &monitor), 1000);

  std::atomic<bool> stop_rx{false}, stop_feed{false};
  std::thread rx_thread([&] { handle_until(rx_lcm, stop_rx); });
  std::thread mon_thread([&] { handle_until(mon_lcm, stop_rx); });
  FeedResult fed;
  std::thread feed_thread([&] { feed(feed_lcm, log, o.feed, monitor, stop_feed, fed); });

  auto shutdown = [&] {
    stop_feed = true;
    feed_thread.join();
    stop_rx = true;
    rx_thread.join();
    mon_thread.join();
  };
  // The optimizer must be running before the measurement starts.
  const auto deadline = Clock::now() + std::chrono::seconds(15);
  while (!o.idle && monitor.newest_keyframe.load() < 0 && Clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  if (!o.idle && monitor.newest_keyframe.load() < 0) {
    shutdown();
    std::fprintf(
        stderr, "daemon_latency: FAIL: no TRAJECTORY of '%s' within 15 s: the daemon's graph back end is not running\n",
        o.fed_source.c_str());
    return 1;
  }
  std::this_thread::sleep_for(std::chrono::duration<double>(o.warmup_s));

  // The sender: odometry k at t0 + k P, the same bytes on the ping channel at t0 + (k + 1/2) P.
  std::vector<int64_t> sent_odo(count, -1), sent_ping(count, -1);
  sextant::bench::OdometryTrackOptions track_options;
  track_options.source = o.source;
  track_options.start_utime = start_utime;
  track_options.period_us = period_us;
  sextant::bench::OdometryTrack track(track_options);
  std::optional<sextant::bench::InertialTrack> inertial;
  if (o.inertial) inertial.emplace(track_options, o.odometry_every, o.gnss_every);
  const double load_begin = load_average();
  const int64_t t_begin = now_ns();
  {
    const auto t0 = Clock::now() + std::chrono::milliseconds(1);
    const std::chrono::microseconds period(period_us);
    for (size_t k = 0; k < count && !g_interrupted.load(); ++k) {
      const Step step = next_step(o, track, inertial, static_cast<int64_t>(k));
      std::this_thread::sleep_until(t0 + period * static_cast<int64_t>(k));
      sent_odo[k] = now_ns();
      for (const auto& [channel, bytes] : step.messages)
        tx_lcm.publish(*channel, bytes.data(), static_cast<unsigned>(bytes.size()));
      std::this_thread::sleep_until(t0 + period * static_cast<int64_t>(k) + period / 2);
      sent_ping[k] = now_ns();
      tx_lcm.publish(o.ping, step.ping.data(), static_cast<unsigned>(step.ping.size()));
    }
  }
  const int64_t t_end = now_ns();
  const double load_end = load_average();
  std::this_thread::sleep_for(std::chrono::duration<double>(o.settle_s));
  shutdown();
  size_t sent = 0;
  while (sent < count && sent_ping[sent] >= 0) ++sent;

  // Latencies.
  std::vector<ChannelResult> channels;
  const auto every = static_cast<size_t>(o.inertial ? o.odometry_every : 1);
  for (const auto& [channel, arrivals] : receiver.arrivals)
    if (channel != o.pong)
      channels.push_back(summarize(channel, "daemon " + receiver.estimator[channel], arrivals, sent_odo, sent, every));
  for (const auto& e : o.expect)
    if (!receiver.arrivals.count(e))
      channels.push_back(summarize(e, "daemon (nothing received)", {}, sent_odo, sent, every));
  const auto pong_it = receiver.arrivals.find(o.pong);
  const ChannelResult raw =
      summarize(o.pong, "raw LCM round trip (echo)",
                pong_it == receiver.arrivals.end() ? std::vector<int64_t>{} : pong_it->second, sent_ping, sent);

  // The optimizer during the measurement [t_begin, t_end].
  const Monitor::Status* before = status_at(monitor.statuses, t_begin);
  const Monitor::Status* after = status_at(monitor.statuses, t_end + static_cast<int64_t>(o.settle_s * 1e9));
  LatencyRecorder solve_ms(std::max<size_t>(1, monitor.solves.size()));
  int64_t solves_fed = 0, solves_body = 0, first_kf = -1, last_kf = -1;
  double busy_ms = 0, last_chi2 = 0;
  for (const auto& s : monitor.solves) {
    if (s.at_ns < t_begin || s.at_ns > t_end) continue;
    busy_ms += s.solve_ms;
    solve_ms.add(s.solve_ms);
    if (s.source == o.fed_source) {
      ++solves_fed;
      if (first_kf < 0) first_kf = s.newest_keyframe;
      last_kf = s.newest_keyframe;
      last_chi2 = s.chi2;
    } else {
      ++solves_body;
    }
  }
  const LatencySummary solve = solve_ms.summary();
  const double window_ms = static_cast<double>(t_end - t_begin) * 1e-6;
  auto delta = [&](const std::string& stage, const std::string& name) {
    return counter(after, stage, name) - counter(before, stage, name);
  };
  int64_t graph_queue_max = 0, odometry_waiting_max = 0;
  for (const auto& s : monitor.statuses)
    if (s.at_ns >= t_begin && s.at_ns <= t_end) {
      graph_queue_max = std::max(graph_queue_max, counter(&s, "graph", "queue_depth"));
      odometry_waiting_max = std::max(odometry_waiting_max, counter(&s, "graph", "odometry_waiting"));
    }
  const double per_minute = 60e3 / window_ms;

  // Report.
  std::printf(
      "daemon latency: %zu %s of '%s' at %.0f Hz over %.1f s; raw round trip: odometry bytes at the same rate\n", sent,
      o.inertial ? "IMU samples (odometry, GNSS at a fraction)" : "odometry messages", o.source.c_str(), o.rate_hz,
      window_ms * 1e-3);
  std::printf("  1-minute load average at the start / end of the measurement: %.2f / %.2f\n", load_begin, load_end);
  std::printf("  %-26s %-28s %8s %6s %8s %8s %8s\n", "channel", "path", "samples", "lost", "p50_ms", "p99_ms",
              "max_ms");
  auto row = [](const ChannelResult& c) {
    std::printf("  %-26s %-28s %8lld %6lld %8.3f %8.3f %8.3f\n", c.channel.c_str(), c.label.c_str(),
                static_cast<long long>(c.received), static_cast<long long>(c.lost), c.latency.p50_ms, c.latency.p99_ms,
                c.latency.max_ms);
  };
  for (const auto& c : channels) row(c);
  row(raw);
  for (const auto& c : channels)
    if (raw.latency.p50_ms > 0 && c.received > 0)
      std::printf("  %-26s daemon/raw: p50 x%.2f, p99 x%.2f\n", c.channel.c_str(),
                  c.latency.p50_ms / raw.latency.p50_ms, c.latency.p99_ms / raw.latency.p99_ms);
  if (o.idle)
    std::printf("optimizer during the measurement (idle baseline: no background body):\n");
  else
    std::printf("optimizer during the measurement (fed body '%s', %lld of %lld poses fed so far%s):\n",
                o.fed_source.c_str(), static_cast<long long>(fed.odometry), static_cast<long long>(fed.total_odometry),
                fed.finished_ns >= 0 && fed.finished_ns < t_end ? ", the whole graph sent BEFORE the end" : "");
  std::printf(
      "  keyframes on TRAJECTORY %lld -> %lld; graph stage: keyframes +%lld, loops accepted +%lld, rejected +%lld, "
      "unmatched +%lld\n",
      static_cast<long long>(first_kf), static_cast<long long>(last_kf),
      static_cast<long long>(delta("graph", "keyframes")), static_cast<long long>(delta("graph", "loops_accepted")),
      static_cast<long long>(delta("graph", "loops_rejected")),
      static_cast<long long>(delta("graph", "loops_unmatched")));
  std::printf(
      "  solves (TRAJECTORY) %lld of the fed body + %lld of '%s'; solve_ms p50 %.2f p99 %.2f max %.2f; busy %.0f %% of "
      "the time; chi2 %.1f\n",
      static_cast<long long>(solves_fed), static_cast<long long>(solves_body), o.source.c_str(), solve.p50_ms,
      solve.p99_ms, solve.max_ms, 100.0 * busy_ms / window_ms, last_chi2);
  std::printf("  per minute: keyframes %.0f, loops accepted %.0f (graph stage counters over the measurement)\n",
              static_cast<double>(delta("graph", "keyframes")) * per_minute,
              static_cast<double>(delta("graph", "loops_accepted")) * per_minute);
  std::printf("  graph queue depth max %lld; dropped: graph +%lld, graph_pose +%lld, filter +%lld\n",
              static_cast<long long>(graph_queue_max), static_cast<long long>(delta("graph", "dropped")),
              static_cast<long long>(delta("graph_pose", "dropped")),
              static_cast<long long>(delta("filter", "dropped")));
  std::printf(
      "  graph odometry: coalesced +%lld (joined a batch waiting for the stage), waiting max %lld (messages in "
      "batches)\n",
      static_cast<long long>(delta("graph", "odometry_coalesced")), static_cast<long long>(odometry_waiting_max));
  const std::array<double, 3> graph_latency =
      after != nullptr && after->latency_ms.count("graph") ? after->latency_ms.at("graph") : std::array<double, 3>{};
  std::printf(
      "  graph stage, event in -> processed (the last 10 s of events, from SEXTANT_STATUS): p50 %.1f ms, p99 %.1f ms, "
      "max %.1f ms\n",
      graph_latency[0], graph_latency[1], graph_latency[2]);
  if (!o.idle && fed.finished_ns >= 0)
    std::printf("  the whole graph was fed %.1f s into the measurement\n",
                static_cast<double>(fed.finished_ns - t_begin) * 1e-9);
  if (receiver.duplicates + receiver.undecodable + receiver.unknown_time > 0)
    std::printf("  receiver: %lld duplicates, %lld undecodable, %lld unknown times\n",
                static_cast<long long>(receiver.duplicates), static_cast<long long>(receiver.undecodable),
                static_cast<long long>(receiver.unknown_time));

  if (!o.json.empty()) {
    sextant::tools::JsonWriter j;
    j.begin_object()
        .field("samples_sent", sent)
        .field("rate_hz", o.rate_hz)
        .field("window_s", window_ms * 1e-3)
        .field("load_begin", load_begin)
        .field("load_end", load_end);
    auto put = [&](const ChannelResult& c) {
      j.key(c.channel)
          .begin_object()
          .field("received", c.received)
          .field("lost", c.lost)
          .field("p50_ms", c.latency.p50_ms)
          .field("p99_ms", c.latency.p99_ms)
          .field("max_ms", c.latency.max_ms)
          .end_object();
    };
    j.key("latency").begin_object();
    for (const auto& c : channels) put(c);
    put(raw);
    j.end_object();
    j.key("optimizer")
        .begin_object()
        .field("fed_poses", fed.odometry)
        .field("total_poses", fed.total_odometry)
        .field("finished_before_end", fed.finished_ns >= 0 && fed.finished_ns < t_end)
        .field("first_keyframe", first_kf)
        .field("last_keyframe", last_kf)
        .field("keyframes_added", delta("graph", "keyframes"))
        .field("loops_accepted", delta("graph", "loops_accepted"))
        .field("loops_rejected", delta("graph", "loops_rejected"))
        .field("solves_fed", solves_fed)
        .field("solves_body", solves_body)
        .field("solve_ms_p50", solve.p50_ms)
        .field("solve_ms_p99", solve.p99_ms)
        .field("solve_ms_max", solve.max_ms)
        .field("busy_fraction", busy_ms / window_ms)
        .field("graph_queue_max", graph_queue_max)
        .field("graph_dropped", delta("graph", "dropped"))
        .field("graph_pose_dropped", delta("graph_pose", "dropped"))
        .field("filter_dropped", delta("filter", "dropped"))
        .field("odometry_coalesced", delta("graph", "odometry_coalesced"))
        .field("odometry_waiting_max", odometry_waiting_max)
        .field("keyframes_per_minute", static_cast<double>(delta("graph", "keyframes")) * per_minute)
        .field("loops_per_minute", static_cast<double>(delta("graph", "loops_accepted")) * per_minute)
        .field("graph_event_latency_ms_p50", graph_latency[0])
        .field("graph_event_latency_ms_p99", graph_latency[1])
        .field("feed_finished_s", fed.finished_ns >= 0 ? static_cast<double>(fed.finished_ns - t_begin) * 1e-9 : -1.0)
        .end_object();
    j.end_object();
    std::ofstream(o.json) << j.str() << "\n";
  }

  if (!o.samples.empty()) {  // one line per message: k, send time [s from the start], latency per channel [ms]
    std::ofstream f(o.samples);
    f << "k,sent_s";
    for (const auto& [channel, arrivals] : receiver.arrivals) f << "," << channel;
    f << "\n";
    for (size_t k = 0; k < sent; ++k) {
      f << k << "," << static_cast<double>(sent_odo[k] - t_begin) * 1e-9;
      for (const auto& [channel, arrivals] : receiver.arrivals) {
        const int64_t s0 = channel == o.pong ? sent_ping[k] : sent_odo[k];
        f << ",";
        if (arrivals[k] >= 0) f << static_cast<double>(arrivals[k] - s0) * 1e-6;
      }
      f << "\n";
    }
  }

  int rc = 0;
  for (const auto& c : channels)
    if (c.received == 0) {
      std::fprintf(stderr, "daemon_latency: FAIL: no fused pose of '%s' on %s\n", o.source.c_str(), c.channel.c_str());
      rc = 1;
    }
  if (channels.empty()) {
    std::fprintf(stderr, "daemon_latency: FAIL: no fused pose of '%s' on any %s* channel\n", o.source.c_str(),
                 o.fused_prefix.c_str());
    rc = 1;
  }
  if (raw.received == 0) {
    std::fprintf(stderr, "daemon_latency: FAIL: no answer on %s: is `daemon_latency echo` running?\n", o.pong.c_str());
    rc = 1;
  }
  if (!o.idle && (solves_fed == 0 || delta("graph", "keyframes") <= 0)) {
    std::fprintf(
        stderr,
        "daemon_latency: FAIL: the optimizer did not run during the measurement (%lld solves, %lld keyframes)\n",
        static_cast<long long>(solves_fed), static_cast<long long>(delta("graph", "keyframes")));
    rc = 1;
  }
  return rc;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"sextantd latency under optimizer load, next to the raw LCM round trip"};
  app.require_subcommand(1);
  std::string url;
  app.add_option("--lcm-url", url, "LCM URL (default: LCM's, or $LCM_DEFAULT_URL)");

  auto* echo = app.add_subcommand("echo", "republish every message of the ping channel on the pong channel");
  std::string ping = "LATENCY_PING", pong = "LATENCY_PONG";
  echo->add_option("--ping", ping, "channel to echo");
  echo->add_option("--pong", pong, "channel of the echo");

  MeasureOptions mo;
  auto* measure = app.add_subcommand("measure", "publish odometry, time the daemon's fused poses and the echo");
  auto* feed_option =
      measure->add_option("--feed", mo.feed.path, "LCM log of the background body (sextant convert g2o)")
          ->check(CLI::ExistingFile);
  measure->add_flag("--idle", mo.idle, "no background body: the baseline with the optimizer idle")
      ->excludes(feed_option);
  measure->add_option("--fed-source", mo.fed_source, "odometry source of the background body in that log");
  measure->add_option("--window", mo.feed.window, "poses fed ahead of the newest optimized keyframe")
      ->check(CLI::PositiveNumber);
  measure->add_option("--feed-rate", mo.feed.max_rate, "largest feeding rate, poses per second")
      ->check(CLI::PositiveNumber);
  measure->add_option("--duration", mo.duration_s, "seconds of measurement")->check(CLI::Range(0.1, 600.0));
  measure->add_option("--rate", mo.rate_hz, "odometry (and ping) rate, Hz")->check(CLI::Range(1.0, 20000.0));
  measure->add_option("--warmup", mo.warmup_s, "seconds of feeding before the measurement")
      ->check(CLI::NonNegativeNumber);
  measure->add_option("--source", mo.source, "odometry source of the measured body");
  measure->add_option("--expect", mo.expect, "fused-pose channels that must deliver (fail otherwise)");
  measure->add_option("--ping", mo.ping, "ping channel");
  measure->add_option("--pong", mo.pong, "echo channel");
  measure->add_flag("--inertial", mo.inertial,
                    "IMU at --rate, odometry with its twist every --odometry-every samples, GNSS every --gnss-every");
  measure->add_option("--odometry-every", mo.odometry_every, "IMU samples per odometry message (--inertial)")
      ->check(CLI::PositiveNumber);
  measure->add_option("--gnss-every", mo.gnss_every, "IMU samples per GNSS fix (--inertial)")
      ->check(CLI::PositiveNumber);
  measure->add_option("--json", mo.json, "write the figures as JSON to this file");
  measure->add_option("--samples", mo.samples, "write every message's latencies as CSV to this file");
  CLI11_PARSE(app, argc, argv);

  if (echo->parsed()) return run_echo(url, ping, pong);
  if (mo.feed.path.empty() && !mo.idle) {
    std::fprintf(stderr, "daemon_latency measure: --feed GRAPH.lcm or --idle is required\n");
    return 2;
  }
  mo.url = url;
  std::signal(SIGINT, [](int) { g_interrupted = true; });
  return run_measure(mo);
}
