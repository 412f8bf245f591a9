#include "report/report.hpp"

#include "daemon/runtime/version.hpp"

#include "report/json_writer.hpp"
#include "report/svg_plot.hpp"
#include "eval/trajectory_eval.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <stdexcept>

namespace sextant::tools {
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

// Ground truth of the robots (all sources together; the simulator and converters have one), by time.
std::vector<StampedPose> robot_truth(const ReplayResult& r) {
  std::vector<StampedPose> truth;
  for (const auto& t : r.truth_poses) truth.push_back({static_cast<double>(t.utime) * 1e-6, t.pose});
  std::sort(truth.begin(), truth.end(), [](const auto& a, const auto& b) { return a.t < b.t; });
  truth.erase(std::unique(truth.begin(), truth.end(), [](const auto& a, const auto& b) { return a.t == b.t; }),
              truth.end());
  return truth;
}

// 1. Top view: landmarks, the truth and every estimator.
SvgPlot top_view(const ReplayResult& r, const std::vector<StampedPose>& truth, const std::string& estimator) {
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
    top.polyline(xy, kColors[color++ % 7], name + (name == estimator ? " (primary)" : ""),
                 name == estimator ? 1.8 : 1.0);
  }
  return top;
}

struct Scores {
  AteResult ate;
  std::optional<RpeResult> rpe;
  std::vector<StampedPose> est;
};

// 2. Every estimator against the truth (TUM/evo definitions): ATE after SE(3) alignment per pose, RPE over 1 s.
std::map<std::string, Scores> score_estimators(const ReplayResult& r, const std::vector<StampedPose>& truth) {
  std::map<std::string, Scores> scores;
  if (truth.empty()) return scores;
  for (const auto& [name, poses] : r.fused_poses) {
    Scores sc;
    sc.est = stamped(poses);
    try {
      sc.ate = absolute_trajectory_error(truth, sc.est);
    } catch (const std::invalid_argument&) {
      continue;  // fewer than 2 poses with truth
    }
    try {
      sc.rpe = relative_pose_error(truth, sc.est, 1.0, DeltaUnit::kSeconds, sc.ate.scale);
    } catch (const std::invalid_argument&) {}
    scores.emplace(name, std::move(sc));
  }
  return scores;
}

// The primary estimator's figures; the unaligned error at the last matched pose (the map frame is the truth's frame at
// the start).
ReportNumbers primary_numbers(const ReplayResult& r, const std::vector<StampedPose>& truth,
                              const std::map<std::string, Scores>& scores, const std::string& estimator) {
  ReportNumbers numbers;
  const auto primary = scores.find(estimator);
  if (primary != scores.end()) {
    const auto& ate = primary->second.ate;
    numbers.poses = primary->second.est.size();
    numbers.have_truth = true;
    numbers.ate_rmse = ate.error.rmse;
    numbers.ate_max = ate.error.max;
    numbers.matched = ate.matched;
    const auto matches = associate(truth, primary->second.est);
    if (!matches.empty())
      numbers.final_error =
          (truth[matches.back().first].pose.position - primary->second.est[matches.back().second].pose.position).norm();
  } else if (const auto it = r.fused_poses.find(estimator); it != r.fused_poses.end()) {
    numbers.poses = it->second.size();
  }
  return numbers;
}

// 2a. The primary estimate, aligned onto the truth, coloured by its error (evo's "trajectory colored by APE").
SvgPlot colored_trajectory(const std::vector<StampedPose>& truth, const std::map<std::string, Scores>& scores,
                           const std::string& estimator) {
  SvgPlot colored("Trajectory of " + estimator + " coloured by its ATE (SE(3)-aligned)", "x [m]", "y [m]");
  colored.set_equal_aspect(true);
  const auto primary = scores.find(estimator);
  if (primary == scores.end()) return colored;
  std::vector<Eigen::Vector2d> xy, gt_xy;
  for (const auto& t : truth) gt_xy.push_back(t.pose.position.head<2>());
  colored.polyline(gt_xy, "#888888", "ground truth", 1.0);
  const auto& ate = primary->second.ate;
  const auto matches = associate(truth, primary->second.est);
  for (const auto& [g, e] : matches)
    xy.push_back((ate.scale * ate.rotation * primary->second.est[e].pose.position + ate.translation).head<2>());
  colored.colored_polyline(xy, ate.errors, "ATE [m]");
  return colored;
}

// The primary's ATE statistics as lines on the error plot: rmse, mean, median, mean ± std.
void primary_statistics(SvgPlot& err, const AteResult& ate, const std::string& estimator) {
  const auto& e = ate.error;
  char label[96];
  std::snprintf(label, sizeof label, "%s rmse %.3f m", estimator.c_str(), e.rmse);
  err.hline(e.rmse, "#000000", label);
  std::snprintf(label, sizeof label, "%s mean %.3f m", estimator.c_str(), e.mean);
  err.hline(e.mean, "#bcbd22", label);
  std::snprintf(label, sizeof label, "%s median %.3f m", estimator.c_str(), e.median);
  err.hline(e.median, "#7f7f7f", label);
  std::snprintf(label, sizeof label, "%s mean \u00b1 std (%.3f m)", estimator.c_str(), e.std);
  err.hband(e.mean - e.std, e.mean + e.std, "#bcbd22", label);
}

// 2b. ATE and RPE over time of every estimator, with the primary's statistics.
std::pair<SvgPlot, SvgPlot> errors_over_time(const std::map<std::string, Scores>& scores, const std::string& estimator,
                                             double t0) {
  SvgPlot err("ATE over time, every estimator (SE(3)-aligned)", "time [s]", "error [m]", 760, 420);
  SvgPlot rpe("RPE over time, every estimator (translation over 1 s)", "time [s]", "error [m]", 760, 420);
  int ci = 0;
  for (const auto& [name, sc] : scores) {
    const std::string& c = kColors[ci++ % 7];
    const bool is_primary = name == estimator;
    std::vector<Eigen::Vector2d> curve;
    for (size_t k = 0; k < sc.ate.errors.size(); ++k) curve.emplace_back(sc.ate.stamps[k] - t0, sc.ate.errors[k]);
    char label[160];
    std::snprintf(label, sizeof label, "%s%s: rmse %.3f m", name.c_str(), is_primary ? " (primary)" : "",
                  sc.ate.error.rmse);
    err.polyline(curve, c, label, is_primary ? 1.8 : 1.0);
    if (sc.rpe) {
      std::vector<Eigen::Vector2d> rc;
      for (size_t k = 0; k < sc.rpe->stamps.size(); ++k)
        rc.emplace_back(sc.rpe->stamps[k] - t0, sc.rpe->translation_errors[k]);
      std::snprintf(label, sizeof label, "%s: rmse %.3f m, %.2f deg", name.c_str(), sc.rpe->translation.rmse,
                    sc.rpe->rotation_deg.rmse);
      rpe.polyline(rc, c, label, is_primary ? 1.8 : 1.0);
    }
  }
  if (const auto primary = scores.find(estimator); primary != scores.end())
    primary_statistics(err, primary->second.ate, estimator);
  return {std::move(err), std::move(rpe)};
}

std::string scores_table_html(const std::map<std::string, Scores>& scores, const std::string& estimator) {
  if (scores.empty()) return {};
  std::string table =
      "<h2>Estimators against the truth</h2>\n<table><tr><th>estimator</th><th>poses</th><th>ATE rmse [m]</th>"
      "<th>mean</th><th>median</th><th>std</th><th>max</th><th>RPE rmse [m / 1 s]</th><th>RPE rot rmse "
      "[deg]</th></tr>\n";
  for (const auto& [name, sc] : scores) {
    char row[512];
    std::snprintf(row, sizeof row,
                  "<td>%zu</td><td>%.4f</td><td>%.4f</td><td>%.4f</td><td>%.4f</td><td>%.4f</td><td>%s</td><td>%s</td>",
                  sc.ate.matched, sc.ate.error.rmse, sc.ate.error.mean, sc.ate.error.median, sc.ate.error.std,
                  sc.ate.error.max, sc.rpe ? std::to_string(sc.rpe->translation.rmse).c_str() : "-",
                  sc.rpe ? std::to_string(sc.rpe->rotation_deg.rmse).c_str() : "-");
    table += "<tr><td>" + html_escape(name) + (name == estimator ? " (primary)" : "") + "</td>" + row + "</tr>\n";
  }
  return table + "</table>\n";
}

// 3. Targets: associated positions of the last 20 scans with 2-sigma ellipses against the targets' truth, framed to
// the truth and the bulk of the estimates (one far ghost must not squeeze the rest into a corner); `note` says what
// fell outside the frame.
SvgPlot targets_plot(const ReplayResult& r, std::string& note) {
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
  const Eigen::Vector4d view = robust_view(truth_targets, estimated, 0.05, 0.15, 2.0);
  size_t outside = 0;
  double farthest = 0;
  for (const auto& p : estimated)
    if (p.x() < view[0] || p.x() > view[1] || p.y() < view[2] || p.y() > view[3]) {
      ++outside;
      farthest = std::max(farthest, p.norm());
    }
  tg.set_view(view[0], view[1], view[2], view[3]);
  if (outside > 0) {
    char b[160];
    std::snprintf(b, sizeof b, "%zu estimate(s) outside this frame, the farthest %.0f m from the origin", outside,
                  farthest);
    note = b;
  }
  return tg;
}

// 4. Latency per stage: a histogram of the processing time per event up to the 99th percentile.
std::string latency_histograms(const ReplayResult& r) {
  std::string svgs;
  for (const auto& s : r.stages) {
    if (s.latency_ms.empty()) continue;
    std::vector<double> l = s.latency_ms;
    std::sort(l.begin(), l.end());
    const double hi =
        std::max(l[std::min(l.size() - 1, static_cast<size_t>(0.99 * static_cast<double>(l.size())))], 1e-6);
    const int bins = 30;
    std::vector<double> edges(bins + 1), counts(bins, 0);
    for (int b = 0; b <= bins; ++b) edges[static_cast<size_t>(b)] = hi * b / bins;
    for (double v : l) counts[static_cast<size_t>(std::min(bins - 1, static_cast<int>(v / hi * bins)))] += 1;
    SvgPlot h("Processing time per event: " + s.name, "milliseconds (to the 99th percentile)", "events", 420, 300);
    h.histogram(edges, counts, "#1f77b4", "");
    svgs += h.render();
  }
  return svgs;
}

// 5. Message counts, rejections and drops per channel: the bar plot (bars: channel index) and the table.
std::pair<SvgPlot, std::string> channel_messages(const ReplayResult& r, double duration) {
  SvgPlot msgs("Input messages per channel", "", "messages");
  std::vector<std::string> channel_names;
  std::vector<double> edges, received, rejected;
  std::string table =
      "<table><tr><th>#</th><th>channel</th><th>received</th><th>decoded</th><th>rejected</th><th>reasons</"
      "th><th>dropped</th><th>rate [Hz]</th></tr>\n";
  int idx = 0;
  for (const auto& [name, c] : r.channels) {
    channel_names.push_back(name);
    edges.push_back(idx), received.push_back(static_cast<double>(c.received)),
        rejected.push_back(static_cast<double>(c.rejected));
    std::string reasons;
    for (const auto& [reason, n] : c.reasons) reasons += reason + " " + std::to_string(n) + " ";
    char rate[32];
    std::snprintf(rate, sizeof rate, "%.1f", static_cast<double>(c.received) / duration);
    table += "<tr><td>" + std::to_string(idx) + "</td><td>" + html_escape(name) + "</td><td>" +
             std::to_string(c.received) + "</td><td>" + std::to_string(c.decoded) + "</td><td>" +
             std::to_string(c.rejected) + "</td><td>" + html_escape(reasons) + "</td><td>" + std::to_string(c.dropped) +
             "</td><td>" + rate + "</td></tr>\n";
    ++idx;
  }
  table += "</table>\n";
  edges.push_back(idx);
  msgs.histogram(edges, received, "#1f77b4", "received");
  std::vector<double> rej_edges;
  for (size_t k = 0; k < edges.size(); ++k) rej_edges.push_back(edges[k] + 0.5);
  msgs.histogram(rej_edges, rejected, "#d62728", "rejected");
  msgs.set_x_categories(channel_names);
  return {std::move(msgs), std::move(table)};
}

// The lines under the title: what was replayed, how fast, and the primary's ATE when there is truth.
std::string headline_html(const ReplayResult& r, const ReportNumbers& numbers, const std::string& estimator,
                          double duration) {
  char headline[512];
  std::snprintf(headline, sizeof headline,
                "%zu log events, %.1f s of data, replayed in %.2f s; primary estimator <b>%s</b> (%zu poses)%s",
                static_cast<size_t>(r.records), duration, r.wall_seconds, html_escape(estimator).c_str(), numbers.poses,
                numbers.have_truth ? "" : "; no ground truth in the log");
  std::string out = "<p>" + std::string(headline) + "</p>\n";
  if (numbers.have_truth) {
    char b[256];
    std::snprintf(b, sizeof b,
                  "<p>ATE (SE(3)-aligned, TUM definition): <b>%.4f m</b> RMSE, max %.4f m over %zu poses; "
                  "unaligned error at the end %.4f m.</p>",
                  numbers.ate_rmse, numbers.ate_max, numbers.matched, numbers.final_error);
    out += b;
  }
  return out;
}

// report.json: the figures of the page for scripts.
std::string report_json(const ReplayResult& r, const ReportNumbers& numbers,
                        const std::map<std::string, Scores>& scores, const std::string& log_name,
                        const std::string& estimator, double duration) {
  JsonWriter j;
  j.begin_object();
  j.field("version", sextant::version());
  j.field("log", log_name).field("estimator", estimator).field("records", r.records).field("duration_s", duration);
  j.field("poses", numbers.poses).field("have_truth", numbers.have_truth);
  if (numbers.have_truth)
    j.field("ate_rmse", numbers.ate_rmse).field("ate_max", numbers.ate_max).field("matched", numbers.matched);
  j.key("estimators").begin_object();
  for (const auto& [name, sc] : scores) {
    j.key(name).begin_object();
    j.field("ate_rmse", sc.ate.error.rmse)
        .field("ate_mean", sc.ate.error.mean)
        .field("ate_median", sc.ate.error.median);
    j.field("ate_std", sc.ate.error.std).field("ate_max", sc.ate.error.max).field("matched", sc.ate.matched);
    if (sc.rpe)
      j.field("rpe_trans_rmse", sc.rpe->translation.rmse).field("rpe_rot_rmse_deg", sc.rpe->rotation_deg.rmse);
    j.end_object();
  }
  j.end_object();
  j.key("channels").begin_object();
  for (const auto& [name, c] : r.channels)
    j.key(name)
        .begin_object()
        .field("received", c.received)
        .field("decoded", c.decoded)
        .field("rejected", c.rejected)
        .field("dropped", c.dropped)
        .end_object();
  j.end_object();
  j.key("published").begin_object();
  for (const auto& [name, n] : r.published_counts) j.field(name, n);
  j.end_object();
  j.field("targets_messages", r.targets.size()).field("trajectories", r.trajectories.size());
  j.end_object();
  return j.str();
}

}  // namespace

ReportNumbers write_report(const std::string& dir, const ReplayResult& r, const std::string& log_name,
                           const std::string& estimator) {
  std::filesystem::create_directories(dir);
  const double t0 = static_cast<double>(r.first_utime) * 1e-6;
  const double duration = std::max(1e-9, static_cast<double>(r.last_utime - r.first_utime) * 1e-6);
  const std::vector<StampedPose> truth = robot_truth(r);
  const auto scores = score_estimators(r, truth);
  const ReportNumbers numbers = primary_numbers(r, truth, scores, estimator);
  const SvgPlot top = top_view(r, truth, estimator);
  const SvgPlot colored = colored_trajectory(truth, scores, estimator);
  const auto [err, rpe] = errors_over_time(scores, estimator, t0);
  std::string targets_note;
  const SvgPlot tg = targets_plot(r, targets_note);
  const auto [msgs, table] = channel_messages(r, duration);
  const std::string html =
      "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>sextant report: " + html_escape(log_name) +
      "</title>\n<style>body{font-family:sans-serif;margin:24px;color:#222} .plot{margin:8px;border:1px solid #ddd}"
      " table{border-collapse:collapse} td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}</style></head>\n"
      "<body>\n<h1>sextant replay report</h1>\n<p>" +
      html_escape(log_name) + " &middot; sextant " + html_escape(sextant::version()) + "</p>\n" +
      headline_html(r, numbers, estimator, duration) + "<div>\n" + top.render() + colored.render() + "</div>\n<div>\n" +
      err.render() + rpe.render() + "</div>\n" + scores_table_html(scores, estimator) + "<div>\n" + tg.render() +
      msgs.render() + "</div>\n" +
      (targets_note.empty() ? "" : "<p>Targets: " + html_escape(targets_note) + ".</p>\n") + table +
      "<h2>Latency</h2>\n<div>\n" + latency_histograms(r) + "</div>\n</body></html>\n";
  write_file(dir + "/index.html", html);
  write_file(dir + "/report.json", report_json(r, numbers, scores, log_name, estimator, duration));
  return numbers;
}

}  // namespace sextant::tools
