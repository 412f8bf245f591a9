#include "estimators/slam/frame_placement.hpp"

#include "estimators/lie/rigid_alignment.hpp"

#include <algorithm>
#include <cmath>

namespace sextant::slam {
namespace {

using Kind = PlacementEvidence::Kind;

bool is_point(const PlacementEvidence& e) { return e.kind != Kind::kLoop; }

double planar_distance(const Eigen::Vector3d& x, const Eigen::Vector3d& y, bool planar) {
  return planar ? (x - y).head<2>().norm() : (x - y).norm();
}

/// Two placements within the inlier thresholds of each other where the evidence lies: the point `at` (in B) lands
/// within inlier_distance under both, and their rotations differ by at most inlier_angle.  Compared at B's origin
/// instead, placements that agree on evidence 30 m away would differ by 0.3 m for every hundredth of a radian.
bool close(const SE3& x, const SE3& y, const Eigen::Vector3d& at, const PlacementOptions& o) {
  return (x * at - y * at).norm() <= o.inlier_distance &&
         (x.rotation().inverse() * y.rotation()).log().norm() <= o.inlier_angle;
}

}  // namespace

bool agrees(const PlacementEvidence& e, const SE3& a_from_b, bool planar, const PlacementOptions& options) {
  if (e.kind == Kind::kLoop) return close(a_from_b, e.a_from_b, e.in_b, options);
  return planar_distance(a_from_b * e.in_b, e.in_a, planar) <= std::max(options.inlier_distance, e.tolerance);
}

namespace {

/// The correspondences (b -> a) that stand for the evidence in a least-squares fit: a point itself, a loop its
/// frame's origin and unit axes.
void add_correspondences(const PlacementEvidence& e, bool planar, std::vector<Eigen::Vector3d>& b,
                         std::vector<Eigen::Vector3d>& a) {
  if (is_point(e)) {
    b.push_back(e.in_b);
    a.push_back(e.in_a);
    return;
  }
  const int axes = planar ? 2 : 3;
  b.push_back(Eigen::Vector3d::Zero());
  for (int k = 0; k < axes; ++k) b.push_back(Eigen::Vector3d::Unit(k));
  for (size_t k = b.size() - static_cast<size_t>(axes) - 1; k < b.size(); ++k) a.push_back(e.a_from_b * b[k]);
}

SE3 fit(const std::vector<const PlacementEvidence*>& es, bool planar) {
  std::vector<Eigen::Vector3d> b, a;
  for (const PlacementEvidence* e : es) add_correspondences(*e, planar, b, a);
  Eigen::Matrix3Xd mb(3, static_cast<Eigen::Index>(b.size())), ma(3, static_cast<Eigen::Index>(a.size()));
  for (size_t k = 0; k < b.size(); ++k)
    mb.col(static_cast<Eigen::Index>(k)) = b[k], ma.col(static_cast<Eigen::Index>(k)) = a[k];
  return align_points(mb, ma, false, planar).motion();
}

/// Point subsets that can form a hypothesis: their points far enough apart and their mutual distances the same in
/// both frames (a rigid motion keeps them).
bool usable(const std::vector<const PlacementEvidence*>& pts, bool planar, const PlacementOptions& o) {
  for (size_t i = 0; i < pts.size(); ++i)
    for (size_t j = i + 1; j < pts.size(); ++j) {
      const double db = planar_distance(pts[i]->in_b, pts[j]->in_b, planar);
      const double da = planar_distance(pts[i]->in_a, pts[j]->in_a, planar);
      if (db < o.min_pair_distance || std::abs(da - db) > 2 * o.inlier_distance) return false;
    }
  if (pts.size() == 3) {  // not collinear: the triangle's height over its longest side at least min_pair_distance / 2
    const Eigen::Vector3d u = pts[1]->in_b - pts[0]->in_b, v = pts[2]->in_b - pts[0]->in_b;
    const double longest = std::max({u.norm(), v.norm(), (v - u).norm()});
    if (u.cross(v).norm() / longest < 0.5 * o.min_pair_distance) return false;
  }
  return true;
}

/// A hypothesis and the size of the sample it was made from (1 loop, or 2 or 3 points): the support it has by
/// construction.
struct Hypothesis {
  SE3 placement;
  int sample = 1;
};

/// Step 1: every loop's placement and every usable pair (planar) or triple (3-D) of points' fit.
std::vector<Hypothesis> hypotheses(const std::vector<const PlacementEvidence*>& es, bool planar,
                                   const PlacementOptions& o) {
  std::vector<Hypothesis> out;
  std::vector<const PlacementEvidence*> points;
  for (const PlacementEvidence* e : es) (is_point(*e) ? points.push_back(e) : out.push_back({e->a_from_b, 1}));
  const size_t n = points.size();
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 1; j < n; ++j) {
      if (planar) {
        if (usable({points[i], points[j]}, planar, o)) out.push_back({fit({points[i], points[j]}, planar), 2});
        continue;
      }
      for (size_t k = j + 1; k < n; ++k)
        if (usable({points[i], points[j], points[k]}, planar, o))
          out.push_back({fit({points[i], points[j], points[k]}, planar), 3});
    }
  return out;
}

/// Where the evidence lies in B: the mean of its points (a loop's: the pose of its end in B).
Eigen::Vector3d centroid_in_b(const std::vector<const PlacementEvidence*>& es) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const PlacementEvidence* e : es) sum += e->in_b;
  return es.empty() ? sum : (sum / static_cast<double>(es.size())).eval();
}

/// The rule's rival: among the hypotheses farther from the best than the inlier thresholds (at `at`, where the best's
/// evidence lies) and confirmed beyond their own sample, the most measurements one explains that the best does not.
/// One that explains the best's own measurements a little differently is the same placement seen through the
/// noise, not a rival: counted on all its support, every hypothesis from a pair of nearby points on collinear
/// evidence 30 m from B's origin would block the decision for ever.
/// `explained[k]`: the best agrees with es[k].
int strongest_rival(const std::vector<const PlacementEvidence*>& es, const std::vector<char>& explained,
                    const std::vector<Hypothesis>& hs, const std::vector<int>& support, size_t best,
                    const Eigen::Vector3d& at, bool planar, const PlacementOptions& o) {
  int strongest = 0;
  for (size_t h = 0; h < hs.size(); ++h) {
    if (support[h] <= hs[h].sample || close(hs[best].placement, hs[h].placement, at, o)) continue;
    int own = 0;
    for (size_t k = 0; k < es.size(); ++k) own += !explained[k] && agrees(*es[k], hs[h].placement, planar, o) ? 1 : 0;
    strongest = std::max(strongest, own);
  }
  return strongest;
}

double spread_of(const std::vector<const PlacementEvidence*>& inliers, bool planar) {
  double spread = 0;
  for (size_t i = 0; i < inliers.size(); ++i)
    for (size_t j = i + 1; j < inliers.size(); ++j)
      if (is_point(*inliers[i]) && is_point(*inliers[j]))
        spread = std::max(spread, planar_distance(inliers[i]->in_b, inliers[j]->in_b, planar));
  return spread;
}

}  // namespace

Placement place_frames(const std::vector<PlacementEvidence>& evidence, bool planar, const PlacementOptions& o) {
  Placement p;
  const size_t first = evidence.size() > static_cast<size_t>(std::max(o.max_evidence, 0))
                           ? evidence.size() - static_cast<size_t>(std::max(o.max_evidence, 0))
                           : 0;
  std::vector<const PlacementEvidence*> es;
  for (size_t k = first; k < evidence.size(); ++k) es.push_back(&evidence[k]);
  const std::vector<Hypothesis> hs = hypotheses(es, planar, o);
  if (hs.empty()) {
    p.reason = "no hypothesis (too few measurements, or too close together)";
    return p;
  }
  // Step 2: support of each hypothesis; the best and its strongest rival (one that some measurement beyond its own
  // sample confirms: a sample always explains itself).
  std::vector<int> support(hs.size(), 0);
  for (size_t h = 0; h < hs.size(); ++h)
    for (const PlacementEvidence* e : es) support[h] += agrees(*e, hs[h].placement, planar, o) ? 1 : 0;
  const size_t best = static_cast<size_t>(std::max_element(support.begin(), support.end()) - support.begin());
  std::vector<char> explained(es.size());
  std::vector<const PlacementEvidence*> inliers;
  for (size_t k = 0; k < es.size(); ++k)
    if ((explained[k] = agrees(*es[k], hs[best].placement, planar, o) ? 1 : 0)) inliers.push_back(es[k]);
  p.rival_support = strongest_rival(es, explained, hs, support, best, centroid_in_b(inliers), planar, o);
  // Step 3: refine on the inliers, and count them again on the refined placement.
  p.a_from_b = fit(inliers, planar);
  inliers.clear();
  for (size_t k = 0; k < es.size(); ++k)
    if (agrees(*es[k], p.a_from_b, planar, o)) inliers.push_back(es[k]), p.inliers.push_back(first + k);
  p.support = static_cast<int>(inliers.size());
  p.spread = spread_of(inliers, planar);
  const bool has_loop = std::any_of(inliers.begin(), inliers.end(), [](auto* e) { return !is_point(*e); });
  // At least min_support, one measurement beyond the sample, and min_inlier_ratio of them all.
  const int needed = std::max({o.min_support, hs[best].sample + 1,
                               static_cast<int>(std::ceil(o.min_inlier_ratio * static_cast<double>(es.size())))});
  if (p.support < needed)
    p.reason = "support " + std::to_string(p.support) + " < " + std::to_string(needed);
  else if (!has_loop && p.spread < o.min_spread)
    p.reason = "inliers span " + std::to_string(p.spread) + " m < " + std::to_string(o.min_spread);
  else if (p.rival_support >= o.rival_ratio * p.support)
    p.reason = "ambiguous: a rival placement has support " + std::to_string(p.rival_support);
  p.placed = p.reason.empty();
  return p;
}

}  // namespace sextant::slam
