// Keyframe thinning: the window and the first keyframe are kept, older keyframes one per place (the earliest), so a
// robot driving laps keeps about one lap of places however many laps it drives.
#include "estimators/keyframe/keyframe_thinning.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <stdexcept>

using namespace sextant;

namespace {

ThinningCandidate at(int64_t id, double x, double y, double yaw) {
  return {id, SE3(SO3::exp(Eigen::Vector3d(0, 0, yaw)), Eigen::Vector3d(x, y, 0))};
}

}  // namespace

TEST_CASE("keyframe thinning: laps of a circle keep one keyframe per place plus the window") {
  // 10 laps of a circle of radius 10 m, a keyframe every 0.25 m (about 251 per lap), heading along the circle.
  std::vector<ThinningCandidate> kfs;
  const double r = 10, step = 0.25;
  const int per_lap = static_cast<int>(2 * M_PI * r / step);
  for (int64_t i = 0; i < 10 * per_lap; ++i) {
    const double a = static_cast<double>(i) * step / r;
    kfs.push_back(at(i, r * std::cos(a), r * std::sin(a), a + M_PI / 2));
  }
  KeyframeThinningOptions o;
  o.window = 100;
  const auto keep = keyframes_to_keep(kfs, true, o);
  REQUIRE(keep.size() == kfs.size());
  CHECK(keep.front() == 1);
  for (size_t i = kfs.size() - 100; i < kfs.size(); ++i) CHECK(keep[i] == 1);
  int kept_old = 0, kept_after_first_lap = 0;
  for (size_t i = 0; i + 100 < kfs.size(); ++i) {
    kept_old += keep[i];
    if (i >= static_cast<size_t>(per_lap)) kept_after_first_lap += keep[i];
  }
  // A 1 m cell holds about 4 keyframes of one lap: the first lap keeps at most one per cell it crosses (a circle of
  // 62.8 m crosses at most ~90 cells of 1 m), later laps keep almost nothing (only places the first lap missed).
  MESSAGE(kept_old << " old keyframes kept, " << kept_after_first_lap << " of them after the first lap");
  CHECK(kept_old <= 100);
  CHECK(kept_old >= 50);
  CHECK(kept_after_first_lap <= 10);
  // The same input keeps the same set.
  CHECK(keyframes_to_keep(kfs, true, o) == keep);
}

TEST_CASE("keyframe thinning: heading sectors and height separate places, bad options are refused") {
  KeyframeThinningOptions o;
  o.window = 1;
  // Same cell, opposite headings: two places.  Same cell and heading: one.
  std::vector<ThinningCandidate> k = {at(0, 0, 0, 0), at(1, 5.2, 5.2, 0.1), at(2, 5.4, 5.3, 0.1 + M_PI),
                                      at(3, 5.5, 5.5, 0.12), at(4, 50, 50, 0)};
  auto keep = keyframes_to_keep(k, true, o);
  CHECK(keep == std::vector<char>{1, 1, 1, 0, 1});
  // 3-D: the same x, y at another height is another place; planar bodies ignore z.
  k[3].pose = SE3(k[1].pose.rotation(), Eigen::Vector3d(5.5, 5.5, 3.0));
  CHECK(keyframes_to_keep(k, false, o)[3] == 1);
  CHECK(keyframes_to_keep(k, true, o)[3] == 0);
  o.window = 0;
  CHECK_THROWS_AS(keyframes_to_keep(k, true, o), std::invalid_argument);
  o.window = 5;
  o.cell_size = 0;
  CHECK_THROWS_AS(keyframes_to_keep(k, true, o), std::invalid_argument);
}
