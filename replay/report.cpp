#include "replay/report.hpp"

#include "daemon/runtime/version.hpp"

#include "replay/json_writer.hpp"
#include "replay/svg_plot.hpp"
#include "replay/trajectory_eval.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>

namespace sextant::replay {
namespace {

const char* kColors[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2"};

std::vector<StampedPose> stamped(const std::vector<engine::FusedPose>& poses) {
  std::vector<StampedPose> out;
  for (const auto& p : poses) out.push_back({static_cast<double>(p.utime) * 1e-6, p.pose});
  return out;
}

void write_file(const std::string& path, const std::string& text) {
  std::ofstream f(path);
  if (!f) throw std::runtime_error("cannot write " + path);
  f << text;
}

}  // namespace

ReportNumbers write_report(const std::string& dir, const ReplayResult& r, const std::string& log_name,
                           const std::string& estimator) {
  std::filesystem::create_directories(dir);
  ReportNumbers numbers;
  const double t0 = static_cast<double>(r.first_utime) * 1e-6;

  // Ground truth of the robots (all sources together; the simulator and converters have one).
  std::vector<StampedPose> truth;
  for (const auto& t : r.truth_poses) truth.push_back({static_cast<double>(t.utime) * 1e-6, t.pose});
  std::sort(truth.begin(), truth.end(), [](const auto& a, const auto& b) { return a.t < b.t; });
  truth.erase(std::unique(truth.begin(), truth.end(), [](const auto& a, const auto& b) { return a.t == b.t; }), truth.end());

  // 1. Top view.
  SvgPlot top("Top view", "x [m]", "y [m]");
  top.set_equal_aspect(true);
  std::vector<Eigen::Vector2d> landmarks;
  for (const auto& p : r.truth_points)
    if (p.kind == "landmark") landmarks.push_back(p.position.head<2>());
  top.points(landmarks, "#999999", "landmarks (truth)", 2.5);
  if (!truth.empty()) {
    std::vector<Eigen::Vector2d> xy;
    for (const auto& t : truth) xy.push_back(t.pose.position.head<2>());
    top.polyline(xy, "#222222", "ground truth", 2.5);
  }
  int color = 0;
  for (const auto& [name, poses] : r.fused_poses) {
    std::vector<Eigen::Vector2d> xy;
    for (const auto& p : poses) xy.push_back(p.pose.position.head<2>());
    top.polyline(xy, kColors[color++ % 7], name + (name == estimator ? " (primary)" : ""), name == estimator ? 1.8 : 1.0);
  }

  // 2. Position error over time (unaligned: the map frame is the truth's frame at the start) and aligned ATE.
  SvgPlot err("Position error of " + estimator, "time [s]", "error [m]");
  const auto it = r.fused_poses.find(estimator);
  std::vector<double> errors;
  if (it != r.fused_poses.end() && !truth.empty()) {
    const auto est = stamped(it->second);
    numbers.poses = est.size();
    const auto matches = associate(truth, est);
    std::vector<Eigen::Vector2d> curve;
    for (const auto& [g, e] : matches) {
      const double d = (truth[g].pose.position - est[e].pose.position).norm();
      curve.emplace_back(est[e].t - t0, d);
      errors.push_back(d);
    }
    err.polyline(curve, kColors[0], "|p_est - p_truth|");
    if (matches.size() >= 2) {
      const auto ate = absolute_trajectory_error(truth, est);
      numbers.have_truth = true;
      numbers.ate_rmse = ate.error.rmse;
      numbers.ate_max = ate.error.max;
      numbers.matched = ate.matched;
      numbers.final_error = errors.back();
    }
  }

  // 3. Targets: associated positions with 2-sigma ellipses against the targets' truth.
  SvgPlot tg("Targets (last 20 scans)", "x [m]", "y [m]");
  tg.set_equal_aspect(true);
  std::vector<Eigen::Vector2d> truth_targets;
  for (const auto& p : r.truth_points)
    if (p.kind == "target") truth_targets.push_back(p.position.head<2>());
  tg.polyline(truth_targets.size() > 1 ? std::vector<Eigen::Vector2d>{} : truth_targets, "#222222", "");
  tg.points(truth_targets, "#bbbbbb", "target truth (whole run)", 1.5);
  std::vector<Eigen::Vector2d> estimated;
  const size_t first = r.targets.size() > 20 ? r.targets.size() - 20 : 0;
  for (size_t k = first; k < r.targets.size(); ++k)
    for (const auto& t : r.targets[k].targets) {
      estimated.push_back(t.position.head<2>());
      tg.ellipse(t.position.head<2>(), t.covariance.topLeftCorner<2, 2>(), 2.0, "#d62728");
    }
  tg.points(estimated, "#d62728", "associated targets (2 sigma)", 2.5);

  // 4. Latency per stage.
  std::string latency_svgs;
  for (const auto& s : r.stages) {
    if (s.latency_ms.empty()) continue;
    std::vector<double> l = s.latency_ms;
    std::sort(l.begin(), l.end());
    const double hi = std::max(l[std::min(l.size() - 1, static_cast<size_t>(0.99 * static_cast<double>(l.size())))], 1e-6);
    const int bins = 30;
    std::vector<double> edges(bins + 1), counts(bins, 0);
    for (int b = 0; b <= bins; ++b) edges[static_cast<size_t>(b)] = hi * b / bins;
    for (double v : l) counts[static_cast<size_t>(std::min(bins - 1, static_cast<int>(v / hi * bins)))] += 1;
    SvgPlot h("Processing time per event: " + s.name, "milliseconds (to the 99th percentile)", "events", 420, 300);
    h.histogram(edges, counts, "#1f77b4", "");
    latency_svgs += h.render();
  }

  // 5. Message counts, rejections and drops per channel (bars: channel index).
  SvgPlot msgs("Input messages per channel", "channel (see the table)", "messages");
  std::vector<double> edges, received, rejected;
  std::string table = "<table><tr><th>#</th><th>channel</th><th>received</th><th>decoded</th><th>rejected</th><th>reasons</th><th>dropped</th><th>rate [Hz]</th></tr>\n";
  const double duration = std::max(1e-9, static_cast<double>(r.last_utime - r.first_utime) * 1e-6);
  int idx = 0;
  for (const auto& [name, c] : r.channels) {
    edges.push_back(idx), received.push_back(static_cast<double>(c.received)), rejected.push_back(static_cast<double>(c.rejected));
    std::string reasons;
    for (const auto& [reason, n] : c.reasons) reasons += reason + " " + std::to_string(n) + " ";
    char rate[32];
    std::snprintf(rate, sizeof rate, "%.1f", static_cast<double>(c.received) / duration);
    table += "<tr><td>" + std::to_string(idx) + "</td><td>" + html_escape(name) + "</td><td>" + std::to_string(c.received) +
             "</td><td>" + std::to_string(c.decoded) + "</td><td>" + std::to_string(c.rejected) + "</td><td>" +
             html_escape(reasons) + "</td><td>" + std::to_string(c.dropped) + "</td><td>" + rate + "</td></tr>\n";
    ++idx;
  }
  table += "</table>\n";
  edges.push_back(idx);
  msgs.histogram(edges, received, "#1f77b4", "received");
  std::vector<double> rej_edges;
  for (size_t k = 0; k < edges.size(); ++k) rej_edges.push_back(edges[k] + (k + 1 < edges.size() ? 0.5 : 0.5));
  msgs.histogram(rej_edges, rejected, "#d62728", "rejected");

  char headline[512];
  std::snprintf(headline, sizeof headline,
                "%zu log events, %.1f s of data, replayed in %.2f s; primary estimator <b>%s</b> (%zu poses)%s",
                static_cast<size_t>(r.records), duration, r.wall_seconds, html_escape(estimator).c_str(), numbers.poses,
                numbers.have_truth ? "" : "; no ground truth in the log");
  std::string ate_line;
  if (numbers.have_truth) {
    char b[256];
    std::snprintf(b, sizeof b, "<p>ATE (SE(3)-aligned, TUM definition): <b>%.4f m</b> RMSE, max %.4f m over %zu poses; "
                               "unaligned error at the end %.4f m.</p>",
                  numbers.ate_rmse, numbers.ate_max, numbers.matched, numbers.final_error);
    ate_line = b;
  }
  std::string html =
      "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>sextant report: " + html_escape(log_name) +
      "</title>\n<style>body{font-family:sans-serif;margin:24px;color:#222} .plot{margin:8px;border:1px solid #ddd}"
      " table{border-collapse:collapse} td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}</style></head>\n"
      "<body>\n<h1>sextant replay report</h1>\n<p>" + html_escape(log_name) + " &middot; sextant " + html_escape(sextant::version()) + "</p>\n<p>" + headline + "</p>\n" + ate_line +
      "<div>\n" + top.render() + err.render() + "</div>\n<div>\n" + tg.render() + msgs.render() + "</div>\n" + table +
      "<h2>Latency</h2>\n<div>\n" + latency_svgs + "</div>\n</body></html>\n";
  write_file(dir + "/index.html", html);

  JsonWriter j;
  j.begin_object();
  j.field("version", sextant::version());
  j.field("log", log_name).field("estimator", estimator).field("records", r.records).field("duration_s", duration);
  j.field("poses", numbers.poses).field("have_truth", numbers.have_truth);
  if (numbers.have_truth) j.field("ate_rmse", numbers.ate_rmse).field("ate_max", numbers.ate_max).field("matched", numbers.matched);
  j.key("channels").begin_object();
  for (const auto& [name, c] : r.channels)
    j.key(name).begin_object().field("received", c.received).field("decoded", c.decoded).field("rejected", c.rejected).field("dropped", c.dropped).end_object();
  j.end_object();
  j.key("published").begin_object();
  for (const auto& [name, n] : r.published_counts) j.field(name, n);
  j.end_object();
  j.field("targets_messages", r.targets.size()).field("trajectories", r.trajectories.size());
  j.end_object();
  write_file(dir + "/report.json", j.str());
  return numbers;
}

}  // namespace sextant::replay
