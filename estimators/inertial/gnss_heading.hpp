#pragma once
// The heading of an estimator's frame in East-North-Up, from GNSS fixes against the estimator's own dead-reckoned
// track: for a body whose yaw is not known in ENU (a yaw-free IMU, a magnetometer far off, wheel odometry alone),
// the estimator runs in its own frame until the track is long enough, then this finds the planar rigid transform
//   enu = Rz(yaw) track + t      (track, enu: the antenna's horizontal position, m)
// that takes the track onto the fixes, so the estimator can re-anchor its state in ENU and only then gate fixes.
//
// Steps (estimate()):
//  1. wait until the track spans `baseline_m` (the largest distance between two of its points), at least
//     `min_fixes` pairs;
//  2. consensus: every pair of points at least baseline_m / 2 apart proposes the yaw that turns the track's chord
//     onto the fixes' chord; each proposal is refined by least squares on the points it explains (Mahalanobis
//     distance under chi-square(2) `inlier_chi2`), and the proposal explaining the most points wins, so that a
//     multipath fix among the first few cannot decide the heading;
//  3. residual check: the winner must explain `min_inlier_fraction` of the points and span the baseline itself,
//     else the estimate waits for more fixes.
// The least-squares fit is the weighted 2-D Procrustes (Umeyama, "Least-squares estimation of transformation
// parameters between two point patterns", PAMI 1991, without scale), each point weighted by w = 1 / sigma^2 with
// sigma^2 the mean of its covariance's eigenvalues plus the track's own `track_sigma`^2:
//   a, b the weighted centroids of track and fixes,  yaw = atan2(sum w (ax by - ay bx), sum w (ax bx + ay by))
//   (over the centred points),  t = b - Rz(yaw) a.
// Its uncertainty (first order): var(yaw) = s^2 / sum w |track - a|^2, the centroid's s^2 / sum w per axis, where s^2
// is the reduced chi-square of the inliers' residuals when above 1 (the fixes scatter more than they state).
// Memory and cost are bounded: the newest `max_fixes` pairs are kept, proposals use at most `max_anchors` of them.
#include <Eigen/Core>

#include <deque>
#include <optional>
#include <vector>

namespace sextant::inertial {

struct GnssHeadingOptions {
  double baseline_m = 20;            // the track must span this before the heading is estimated, m
  int min_fixes = 5;                 // and hold this many fixes
  int max_fixes = 120;               // pairs kept (the oldest are dropped)
  int max_anchors = 40;              // points proposals are drawn from (evenly spaced among those kept)
  double track_sigma = 0.5;          // the dead-reckoned track's own error over the baseline, m (added to each fix's)
  double inlier_chi2 = 9.21;         // chi-square(2) 99 %: a point farther than this from the fit is an outlier
  double min_inlier_fraction = 0.6;  // of the points kept
};

/// Throws std::invalid_argument naming the first option out of range.
void check_options(const GnssHeadingOptions& o);

/// enu = Rz(yaw) track + translation, with its first-order uncertainty.
struct PlanarAlignment {
  double yaw = 0;                                            // rad, counter-clockwise (about Up)
  Eigen::Vector2d translation = Eigen::Vector2d::Zero();     // m
  double yaw_sigma = 0;                                      // rad
  Eigen::Vector2d track_centroid = Eigen::Vector2d::Zero();  // m, the weighted centroid of the inliers' track
  double centroid_variance = 0;                              // m^2 per axis, of the aligned centroid
  int inliers = 0, points = 0;
  double rms = 0;  // m, the inliers' residuals

  Eigen::Matrix2d rotation() const;
  /// A track point in ENU.
  Eigen::Vector2d apply(const Eigen::Vector2d& track) const;
  /// Covariance (m^2) of apply(track): the centroid's, and the yaw's lever from the centroid.
  Eigen::Matrix2d covariance_at(const Eigen::Vector2d& track) const;
};

class GnssHeadingAlignment {
 public:
  /// Throws std::invalid_argument for options out of range.
  explicit GnssHeadingAlignment(const GnssHeadingOptions& options = {});

  /// One fix: the antenna's dead-reckoned horizontal position in the estimator's frame at the fix's time (m), the
  /// fix's East-North (m) and its horizontal covariance (m^2).  Returns the alignment once one is found (and every
  /// later call until reset(), without refitting); non-finite input is ignored.
  std::optional<PlanarAlignment> add(const Eigen::Vector2d& track, const Eigen::Vector2d& fix,
                                     const Eigen::Matrix2d& covariance);
  /// The alignment from the pairs held now (steps 1-3), whether or not one was found before.
  std::optional<PlanarAlignment> estimate() const;
  const std::optional<PlanarAlignment>& alignment() const { return found_; }
  size_t size() const { return pairs_.size(); }
  void reset();

  /// The weighted least-squares fit (no outlier handling) of the points whose mask is set; empty when they do not
  /// determine a yaw (fewer than 2, or all at one place).
  struct Pair {
    Eigen::Vector2d track, fix;
    double weight = 0;  // 1 / m^2
  };
  static std::optional<PlanarAlignment> fit(const std::deque<Pair>& pairs, const std::vector<bool>& use);

 private:
  struct Candidate {
    PlanarAlignment alignment;
    std::vector<bool> inliers;
  };
  std::vector<bool> explained(const PlanarAlignment& a) const;
  /// Step 2 for the chord between pairs i and j: its yaw, then least squares on the points it explains, twice more.
  std::optional<Candidate> refine(size_t i, size_t j) const;
  /// The largest distance between two track points of the mask, m.
  double span(const std::vector<bool>& use) const;

  GnssHeadingOptions o_;
  std::deque<Pair> pairs_;
  std::optional<PlanarAlignment> found_;
};

}  // namespace sextant::inertial
