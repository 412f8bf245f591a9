#pragma once
// Where one map frame lies in another, from the measurements that connect them, and the rule that decides when that
// placement is known well enough for two robots' maps to become one.
//
// Each robot of a fleet starts in its own odometry frame; nothing says where the frames are relative to each other.
// What connects two frames A and B is evidence of their placement T_AB (a point in B maps to A as T_AB p):
//  - a landmark both maps hold (same id): its position in A and in B, a point correspondence;
//  - a robot's sighting of another robot: where the sighting puts the seen robot, in the observer's frame, and where
//    the seen robot's own graph has it at that time, in its frame: a point correspondence;
//  - a loop closure between two robots: T_AB = X_a z X_b^-1 directly (X the two poses in their frames).
// Any of them can be wrong (a misread landmark id, a false match), and one wrong placement folds two maps into
// one that no later measurement can unfold.  So the placement is found by consensus, as RANSAC does:
//  1. hypotheses: every loop's placement, and every pair (planar; every triple in 3-D) of point correspondences
//     whose points are at least `min_pair_distance` apart and whose mutual distances agree in both frames;
//  2. each hypothesis's support: the measurements it explains, a point within `inlier_distance` (or its own
//     tolerance, when larger) of its counterpart,
//     a loop within `inlier_distance` and `inlier_angle` of the hypothesis;
//  3. the best (most support; ties: the first) is refined by least squares over its inliers (a loop counts as the
//     correspondences of its frame's origin and unit axes; rigid_alignment.hpp).
// The rule: the frames are placed when the best hypothesis is supported by at least `min_support` measurements, by
// at least one beyond the sample it was made from and by at least `min_inlier_ratio` of all the measurements (maps
// that only look alike -- the same ids at unrelated places -- agree by chance on a few points, never on most), its
// inlier points span at least `min_spread` metres (or a loop
// is among them: a loop alone fixes the rotation), and no rival -- a hypothesis farther than the inlier thresholds
// from the best where the best's evidence lies (its inliers' centroid in B, and the rotation), confirmed by some
// measurement beyond its own sample -- explains `rival_ratio` of the best's support or more among the measurements
// the best does not explain (maps that look alike in two ways split the evidence between two placements; a
// hypothesis explaining the best's own measurements a little differently is the same placement through the noise).
// Until then the frames stay apart.
#include "estimators/lie/se3.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace sextant::slam {

/// One measurement connecting frames A and B.
struct PlacementEvidence {
  enum class Kind { kLandmark, kBodySighting, kLoop };
  Kind kind = Kind::kLandmark;
  /// Points (metres); kLoop: the loop's two ends (where the placement it implies is compared with others).
  Eigen::Vector3d in_a = Eigen::Vector3d::Zero(), in_b = Eigen::Vector3d::Zero();
  SE3 a_from_b;  // kLoop: T_AB it implies
  /// Points: the distance within which this measurement agrees (m); 0: inlier_distance.  A sighting far away is
  /// uncertain by more than a near one (its bearing's error times its range): its own 3-sigma, never less than
  /// inlier_distance.
  double tolerance = 0;
};

struct PlacementOptions {
  int min_support = 3;             // measurements that must agree
  double min_inlier_ratio = 0.5;   // ... and this share of all of them
  double inlier_distance = 0.5;    // m
  double inlier_angle = 0.15;      // rad (loops)
  double min_spread = 1.0;         // m: the inlier points' largest distance from each other (without a loop)
  double min_pair_distance = 0.5;  // m: points of a hypothesis at least this far apart
  double rival_ratio = 0.5;        // a rival with this share of the best's support blocks the decision
  int max_evidence = 64;           // newest measurements considered (bounds the work: O(n^3) planar, O(n^4) 3-D)
};

struct Placement {
  bool placed = false;
  SE3 a_from_b;                 // T_AB, refined on the inliers
  std::vector<size_t> inliers;  // indices into the evidence
  int support = 0;
  int rival_support = 0;  // the strongest rival's measurements that the best does not explain
  double spread = 0;
  std::string reason;  // why not placed ("" when placed)
};

/// Whether one measurement agrees with the placement T_AB (step 2's test: a point within its tolerance, a loop within
/// the inlier distance and angle).
bool agrees(const PlacementEvidence& e, const SE3& a_from_b, bool planar, const PlacementOptions& options);

/// The placement of frame B in frame A from `evidence` (oldest first; only the newest max_evidence are used) by the
/// rule above.  `planar`: SE(2) hypotheses (z and the tilt ignored).
Placement place_frames(const std::vector<PlacementEvidence>& evidence, bool planar, const PlacementOptions& options);

}  // namespace sextant::slam
