// sextant watch: one live line per SEXTANT_STATUS report (message rates, the latest fused pose, targets, drops),
// and a summary when it stops.
#include "daemon/runtime/raw_subscription.hpp"
#include "daemon/runtime/wire_layout.hpp"
#include "cli/command.hpp"
#include "cli/handle_until_stopped.hpp"

#include <sextant/fused_pose_t.hpp>
#include <sextant/status_t.hpp>
#include <sextant/targets_t.hpp>
#include <sextant/trajectory_t.hpp>

#include <lcm/lcm-cpp.hpp>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <map>

namespace {

struct Watcher {
  std::string fused_channel, status_channel, targets_channel, trajectory_channel;
  bool tty = false;
  sextant::fused_pose_t pose{};
  bool have_pose = false;
  int64_t fused = 0, targets_msgs = 0, last_targets = 0, trajectories = 0, last_keyframes = 0;
  sextant::status_t last_status{};
  bool have_status = false;
  std::map<std::string, int64_t> previous_received;
  double previous_uptime = 0;

  template <class Msg>
  static bool decode(const lcm_recv_buf_t& b, Msg& m) {
    return !sextant::runtime::safe_decode(b.data, b.data_size, m);
  }

  void on_message(const lcm_recv_buf_t& b, const std::string& channel) {
    if (channel == fused_channel && decode(b, pose)) {
      have_pose = true;
      ++fused;
    } else if (channel == targets_channel) {
      sextant::targets_t t;
      if (decode(b, t)) ++targets_msgs, last_targets = t.num_targets;
    } else if (channel == trajectory_channel) {
      sextant::trajectory_t t;
      if (decode(b, t)) ++trajectories, last_keyframes = t.num_keyframes;
    } else if (channel == status_channel) {
      sextant::status_t s;
      if (!decode(b, s)) return;
      if (!have_status) std::printf("%s %s\n", s.sender.c_str(), s.version.c_str());  // which daemon, which build
      print_line(s);
      last_status = s;
      have_status = true;
    }
  }

  void print_line(const sextant::status_t& s) {
    const double dt = s.uptime_s - previous_uptime;
    std::string rates;
    int64_t rejected = 0, dropped = 0;
    for (const auto& c : s.channels) {
      const double hz = dt > 0 ? static_cast<double>(c.received - previous_received[c.channel]) / dt : 0;
      previous_received[c.channel] = c.received;
      char buf[64];
      std::snprintf(buf, sizeof buf, "%s %.0f Hz  ", c.channel.c_str(), hz);
      if (c.received > 0) rates += buf;
      rejected += c.rejected;
      dropped += c.dropped;
    }
    for (const auto& st : s.stages) dropped += st.dropped;
    previous_uptime = s.uptime_s;
    char posebuf[128] = "no pose yet";
    if (have_pose) {
      const double* q = pose.orientation;
      const double yaw = std::atan2(2 * (q[0] * q[3] + q[1] * q[2]), 1 - 2 * (q[2] * q[2] + q[3] * q[3]));
      std::snprintf(posebuf, sizeof posebuf, "%s (%.2f, %.2f, %.2f) yaw %.0f deg", pose.estimator.c_str(),
                    pose.position[0], pose.position[1], pose.position[2], yaw * 180 / M_PI);
    }
    std::printf("%s[%6.1f s] %s| pose %s | targets %lld | keyframes %lld | rejected %lld dropped %lld%s",
                tty ? "\r\033[K" : "", s.uptime_s, rates.c_str(), posebuf, (long long)last_targets,
                (long long)last_keyframes, (long long)rejected, (long long)dropped, tty ? "" : "\n");
    std::fflush(stdout);
  }

  void print_summary() const {
    if (tty) std::printf("\n");
    std::printf("watched: %lld fused poses, %lld target reports, %lld trajectories\n", (long long)fused,
                (long long)targets_msgs, (long long)trajectories);
    if (!have_status) return;
    for (const auto& c : last_status.channels)
      std::printf("  in  %-14s received %7lld decoded %7lld rejected %5lld dropped %5lld\n", c.channel.c_str(),
                  (long long)c.received, (long long)c.decoded, (long long)c.rejected, (long long)c.dropped);
    for (size_t i = 0; i < last_status.output_channels.size(); ++i)
      std::printf("  out %-24s %7lld messages\n", last_status.output_channels[i].c_str(),
                  (long long)last_status.output_counts[i]);
    for (const auto& st : last_status.stages)
      if (st.name != "runtime")
        std::printf("  stage %-16s processed %7lld dropped %5lld latency p50 %.3f ms p99 %.3f ms max %.3f ms\n",
                    st.name.c_str(), (long long)st.processed, (long long)st.dropped, st.latency_ms_p50,
                    st.latency_ms_p99, st.latency_ms_max);
  }
};

sextant::cli::RegisterCommand reg{
    "watch", [](CLI::App& app) {
      auto* cmd =
          app.add_subcommand("watch", "a live one-line view of a running sextantd (rates, pose, targets, drops)");
      auto url = std::make_shared<std::string>();
      auto prefix = std::make_shared<std::string>();
      auto seconds = std::make_shared<double>(0);
      cmd->add_option("--lcm-url", *url, "LCM URL");
      cmd->add_option("--prefix", *prefix, "channel prefix of the daemon (channels.prefix)");
      cmd->add_option("--seconds", *seconds, "stop after this many seconds (default: until SIGINT/SIGTERM)");
      cmd->callback([=] {
        lcm::LCM lcm(*url);
        if (!lcm.good()) {
          std::fprintf(stderr,
                       "sextant watch: cannot start LCM (no multicast route? sudo ip route add 224.0.0.0/4 dev lo)\n");
          throw CLI::RuntimeError(3);
        }
        Watcher w;
        w.fused_channel = *prefix + "FUSED_POSE";
        w.status_channel = *prefix + "SEXTANT_STATUS";
        w.targets_channel = *prefix + "TARGETS";
        w.trajectory_channel = *prefix + "TRAJECTORY";
        w.tty = isatty(STDOUT_FILENO) != 0;
        for (const auto* c : {&w.fused_channel, &w.status_channel, &w.targets_channel, &w.trajectory_channel})
          sextant::runtime::subscribe_raw(lcm, *c, &w);
        sextant::cli::handle_until_stopped(lcm, *seconds);
        w.print_summary();
      });
    }};

}  // namespace
