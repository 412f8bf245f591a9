#include "estimators/slam/frame_placement.hpp"

#include <doctest/doctest.h>

#include <random>

using namespace sextant;
using namespace sextant::slam;

namespace {

SE3 planar_pose(double x, double y, double yaw) {
  return SE3(SO3(Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()))), Eigen::Vector3d(x, y, 0));
}

/// A point correspondence of a point `in_b` under the placement `t` (in_a = t in_b), with planar noise.
PlacementEvidence point(const SE3& t, const Eigen::Vector3d& in_b, std::mt19937& rng, double sigma = 0.05) {
  std::normal_distribution<double> n(0, sigma);
  PlacementEvidence e;
  e.in_b = in_b;
  e.in_a = t * in_b + Eigen::Vector3d(n(rng), n(rng), 0);
  return e;
}

}  // namespace

TEST_CASE("frame placement: consensus over landmarks, robot sightings and loops, by the stated rule") {
  std::mt19937 rng(7);
  const SE3 truth = planar_pose(4, -3, 2.0);
  const PlacementOptions o;
  SUBCASE("three landmarks that agree and span more than a metre place the frame") {
    std::vector<PlacementEvidence> e{point(truth, {0, 0, 0}, rng), point(truth, {2, 0, 0}, rng),
                                     point(truth, {1, 3, 0}, rng)};
    const Placement p = place_frames(e, true, o);
    CHECK(p.placed);
    CHECK(p.support == 3);
    CHECK((p.a_from_b.translation() - truth.translation()).norm() < 0.15);
    CHECK((p.a_from_b.inverse() * truth).rotation().log().norm() < 0.05);
  }
  SUBCASE("two landmarks are not enough (support below 3)") {
    std::vector<PlacementEvidence> e{point(truth, {0, 0, 0}, rng), point(truth, {2, 0, 0}, rng)};
    const Placement p = place_frames(e, true, o);
    CHECK_FALSE(p.placed);
    CHECK(p.reason.find("support") != std::string::npos);
  }
  SUBCASE("points packed within the spread do not fix the rotation") {
    std::vector<PlacementEvidence> e{point(truth, {0, 0, 0}, rng, 0.01), point(truth, {0.6, 0, 0}, rng, 0.01),
                                     point(truth, {0.3, 0.55, 0}, rng, 0.01)};
    const Placement p = place_frames(e, true, o);
    CHECK_FALSE(p.placed);
    CHECK(p.reason.find("span") != std::string::npos);
  }
  SUBCASE("a wrong landmark id (one outlier among five) is left out and does not bend the placement") {
    std::vector<PlacementEvidence> e{point(truth, {0, 0, 0}, rng), point(truth, {2, 0, 0}, rng),
                                     point(truth, {1, 3, 0}, rng), point(truth, {-2, 1, 0}, rng)};
    PlacementEvidence wrong = point(truth, {3, 3, 0}, rng);
    wrong.in_a += Eigen::Vector3d(2.5, -1.0, 0);
    e.insert(e.begin() + 2, wrong);
    const Placement p = place_frames(e, true, o);
    CHECK(p.placed);
    CHECK(p.support == 4);
    CHECK(std::find(p.inliers.begin(), p.inliers.end(), size_t{2}) == p.inliers.end());
    CHECK((p.a_from_b.translation() - truth.translation()).norm() < 0.15);
  }
  SUBCASE("two placements with equal support (a symmetric, ambiguous scene): not decided") {
    // Frame B's points seen at the truth, and as many at another placement: no majority.
    const SE3 other = planar_pose(-6, 2, -1.0);
    std::vector<PlacementEvidence> e{point(truth, {0, 0, 0}, rng),   point(truth, {3, 0, 0}, rng),
                                     point(truth, {1, 3, 0}, rng),   point(other, {10, 10, 0}, rng),
                                     point(other, {13, 10, 0}, rng), point(other, {11, 13, 0}, rng)};
    const Placement p = place_frames(e, true, o);
    CHECK_FALSE(p.placed);
    CHECK(p.reason.find("ambiguous") != std::string::npos);
  }
  SUBCASE("evidence far from B's origin: placements that agree on it are not rivals") {
    // Robot sightings 30-40 m from B's origin, each good to its 3-sigma of 0.5 m.  Two hypotheses from different
    // pairs differ by a hundredth of a radian, which moves B's origin by more than inlier_distance but the evidence
    // by millimetres: that is one placement known to within the noise, not two.
    std::vector<PlacementEvidence> e;
    for (int k = 0; k < 24; ++k) {
      const double s = 0.4 * k;
      e.push_back(point(truth, {25 + s, 20 + 0.3 * s, 0}, rng, 0.12));
      e.back().kind = PlacementEvidence::Kind::kBodySighting;
      e.back().tolerance = 0.5;
    }
    const Placement p = place_frames(e, true, o);
    CHECK_MESSAGE(p.placed, p.reason);
    CHECK(p.rival_support == 0);
    CHECK((p.a_from_b * Eigen::Vector3d(30, 21.5, 0) - truth * Eigen::Vector3d(30, 21.5, 0)).norm() < 0.1);
  }
  SUBCASE("a loop and two agreeing robot sightings place the frame; a wrong loop alone does not") {
    PlacementEvidence loop;
    loop.kind = PlacementEvidence::Kind::kLoop;
    loop.a_from_b = truth * planar_pose(0.05, -0.05, 0.02);
    std::vector<PlacementEvidence> e{loop, point(truth, {1, 1, 0}, rng), point(truth, {0, 0.2, 0}, rng)};
    e[1].kind = e[2].kind = PlacementEvidence::Kind::kBodySighting;
    const Placement p = place_frames(e, true, o);
    CHECK(p.placed);
    CHECK((p.a_from_b.translation() - truth.translation()).norm() < 0.15);
    PlacementEvidence wrong = loop;
    wrong.a_from_b = planar_pose(0, 0, 0);
    CHECK_FALSE(place_frames({wrong}, true, o).placed);
    // The wrong loop among true evidence is an outlier.
    e.push_back(wrong);
    const Placement q = place_frames(e, true, o);
    CHECK(q.placed);
    CHECK(q.support == 3);
  }
  SUBCASE("3-D: triples of points") {
    Vector6d xi;
    xi << 1, 2, -0.5, 0.1, -0.2, 0.9;
    const SE3 t = SE3::exp(xi);
    std::vector<PlacementEvidence> e;
    for (const Eigen::Vector3d& q :
         {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(2, 0, 0.5), Eigen::Vector3d(0, 2, 1), Eigen::Vector3d(1, 1, -1)}) {
      PlacementEvidence x;
      x.in_b = q;
      x.in_a = t * q;
      e.push_back(x);
    }
    const Placement p = place_frames(e, false, o);
    CHECK(p.placed);
    CHECK((p.a_from_b.translation() - t.translation()).norm() < 1e-6);
  }
}
