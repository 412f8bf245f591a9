#pragma once
// The replay report: one self-contained HTML page (inline SVG, no scripts, no network) and report.json with the
// same numbers.  Plots: top view of the estimates against ground truth and landmarks; position error over time;
// associated targets with 2-sigma covariance ellipses against the targets' truth; per-stage latency histograms;
// message counts, rejections and drops per channel.
#include "replay/replay_driver.hpp"

#include <string>

namespace sextant::replay {

struct ReportNumbers {
  bool have_truth = false;
  double ate_rmse = 0, ate_max = 0;  // aligned (TUM ATE), metres
  double final_error = 0;            // unaligned, at the last pose
  size_t matched = 0;
  size_t poses = 0;
};

/// Writes DIR/index.html and DIR/report.json (DIR is created); returns the headline numbers.
/// Throws std::runtime_error when the files cannot be written.
ReportNumbers write_report(const std::string& dir, const ReplayResult& result, const std::string& log_name,
                           const std::string& estimator);

}  // namespace sextant::replay
