#pragma once
// The KITTI odometry benchmark's error (Geiger, Lenz, Urtasun, "Are we ready for autonomous driving? The KITTI vision
// benchmark suite", CVPR 2012, section 3.2; the devkit's evaluate_odometry): drift per distance travelled, averaged
// over all sub-sequences of 100, 200, ..., 800 m.
//  - Path length along the ground truth: d_0 = 0, d_i = d_{i-1} + |t_i - t_{i-1}| (gt positions).
//  - Segments: every `step`-th frame f (default 10) and each length L; the segment ends at the first frame l with
//    d_l > d_f + L (no segment when the run is shorter).
//  - Error of a segment: E = (P_f^-1 P_l)^-1 (Q_f^-1 Q_l), P the estimate, Q the ground truth; translational error
//    |t_E| / L, rotational error angle(R_E) / L with angle = acos(clamp((tr R_E - 1) / 2, -1, 1)).
//  - The benchmark's figures: the mean over all segments of both, translation in percent, rotation in degrees per
//    metre (the devkit reports radians per metre in its text files and degrees per metre on the leaderboard).
// Poses are taken pairwise in the given order (frame i of the estimate against frame i of the ground truth): callers
// associate by time first (trajectory_eval.hpp) or read two KITTI files of the same sequence.
#include "eval/trajectory_io.hpp"

#include <vector>

namespace sextant::tools {

struct KittiSegmentError {
  size_t first_frame = 0;
  double length = 0;       // metres (the nominal L)
  double translation = 0;  // |t_E| / L, dimensionless (0.01 = 1 %)
  double rotation = 0;     // angle(R_E) / L, radians per metre
};

struct KittiOdometryError {
  double translation_percent = 0;  // mean over segments of |t_E| / L, x 100
  double rotation_deg_per_m = 0;   // mean over segments of angle(R_E) / L, in degrees per metre
  std::vector<KittiSegmentError> segments;
};

struct KittiMetricOptions {
  std::vector<double> lengths{100, 200, 300, 400, 500, 600, 700, 800};  // metres
  size_t step = 10;                                                     // frames between segment starts
};

/// The KITTI error of `est` against `gt`, pose i with pose i.  Throws std::invalid_argument when the two differ in
/// length, when `options` is unusable (no length, a non-positive length, step 0), or when no segment fits (the run is
/// shorter than the shortest length): a benchmark figure over nothing would read as perfect.
KittiOdometryError kitti_odometry_error(const std::vector<engine::Pose>& gt, const std::vector<engine::Pose>& est,
                                        const KittiMetricOptions& options = {});

}  // namespace sextant::tools
