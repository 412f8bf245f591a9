#pragma once
// The replay report: one self-contained HTML page (inline SVG, no scripts, no network) and report.json with the
// same numbers, at the level of evo's plots.  Top view of every estimate against ground truth and landmarks; the
// primary estimate aligned onto the truth and coloured by its ATE; ATE over time of every estimator (TUM/evo: SE(3)
// alignment) with the primary's rmse, mean, median and mean ± std; RPE over time (translation over 1 s) of every
// estimator; a table of every estimator's ATE and RPE statistics; associated targets with 2-sigma ellipses against
// the targets' truth, framed to the truth and the bulk of the estimates (far ghosts are counted, not framed);
// per-stage latency histograms; messages, rejections and drops per channel, the bars named by channel.
#include "replay/replay_driver.hpp"

#include <string>

namespace sextant::tools {

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

}  // namespace sextant::tools
