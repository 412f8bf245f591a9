// The heading of an estimator's frame from GNSS fixes against its dead-reckoned track: a track rotated by a known
// angle (0, 90, 160, -170 degrees) and shifted, with fix noise and a multipath outlier among the first fixes, gives
// the angle back within its stated uncertainty; nothing is decided before the baseline; the stated sigma matches the
// scatter over many noise draws; the least-squares fit equals a brute-force search over the yaw.
#include "estimators/inertial/gnss_heading.hpp"

#include <doctest/doctest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

using namespace sextant::inertial;

namespace {

constexpr double kDeg = std::numbers::pi / 180;

// A path of a ground robot in its own frame, a point per metre: 25 m ahead, then a quarter circle of 10 m radius to
// the left, then ahead again.
std::vector<Eigen::Vector2d> track(int points) {
  std::vector<Eigen::Vector2d> out;
  for (int k = 0; k < points; ++k) {
    const double s = k;
    if (s <= 25) {
      out.emplace_back(s, 0);
    } else if (s <= 25 + 5 * std::numbers::pi) {
      const double a = (s - 25) / 10;
      out.emplace_back(25 + 10 * std::sin(a), 10 - 10 * std::cos(a));
    } else {
      out.emplace_back(35, 10 + s - 25 - 5 * std::numbers::pi);
    }
  }
  return out;
}

Eigen::Vector2d rotated(double yaw, const Eigen::Vector2d& p) { return Eigen::Rotation2Dd(yaw) * p; }

double wrapped(double a) { return std::remainder(a, 2 * std::numbers::pi); }

// Feeds the track's points with fixes Rz(yaw) p + shift + noise (sigma per axis), the fix at `outlier` 30 m off;
// returns the alignment once found and how many fixes that took.
std::pair<std::optional<PlanarAlignment>, int> run(double yaw, double sigma, int outlier, uint32_t seed,
                                                   const GnssHeadingOptions& o = {}) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0, sigma);
  GnssHeadingAlignment align(o);
  const Eigen::Vector2d shift(-120, 45);
  const auto points = track(60);
  for (int k = 0; k < static_cast<int>(points.size()); ++k) {
    Eigen::Vector2d fix = rotated(yaw, points[k]) + shift + Eigen::Vector2d(n(rng), n(rng));
    if (k == outlier) fix += Eigen::Vector2d(30, -20);
    if (auto a = align.add(points[k], fix, sigma * sigma * Eigen::Matrix2d::Identity())) return {a, k + 1};
  }
  return {std::nullopt, static_cast<int>(points.size())};
}

}  // namespace

TEST_CASE("gnss heading: a rotated, shifted track with noise and one early outlier gives the rotation back") {
  for (double deg : {0.0, 90.0, 160.0, -170.0}) {
    CAPTURE(deg);
    const auto [a, used] = run(deg * kDeg, 1.0, 2, 11);
    REQUIRE(a.has_value());
    CHECK(used >= 21);  // not before the 20 m baseline
    CHECK(std::abs(wrapped(a->yaw - deg * kDeg)) < 3 * a->yaw_sigma);
    CHECK(std::abs(wrapped(a->yaw - deg * kDeg)) < 8 * kDeg);
    CHECK(a->yaw_sigma < 5 * kDeg);
    CHECK(a->inliers == a->points - 1);  // the outlier is out of the consensus
    // The aligned track follows the true fixes (without noise) within the stated covariance.
    const Eigen::Vector2d p = track(60)[static_cast<size_t>(used - 1)];
    const Eigen::Vector2d e = a->apply(p) - (rotated(deg * kDeg, p) + Eigen::Vector2d(-120, 45));
    CHECK(e.dot(a->covariance_at(p).inverse() * e) < 13.8);  // chi-square(2) 99.9 %
  }
}

TEST_CASE("gnss heading: no heading before the track spans the baseline, nor from a track standing still") {
  GnssHeadingAlignment align;
  for (int k = 0; k < 20; ++k)  // 19 m
    CHECK_FALSE(align.add(Eigen::Vector2d(k, 0), Eigen::Vector2d(0, k), Eigen::Matrix2d::Identity()));
  CHECK(align.add(Eigen::Vector2d(20, 0), Eigen::Vector2d(0, 20), Eigen::Matrix2d::Identity()).has_value());
  CHECK(std::abs(align.alignment()->yaw - std::numbers::pi / 2) < 1e-9);

  GnssHeadingAlignment still;
  for (int k = 0; k < 200; ++k)
    CHECK_FALSE(still.add(Eigen::Vector2d::Zero(), Eigen::Vector2d(k % 3, 0), Eigen::Matrix2d::Identity()));
  CHECK(still.size() == static_cast<size_t>(GnssHeadingOptions{}.max_fixes));  // bounded
}

TEST_CASE("gnss heading: when most early fixes disagree, it waits rather than deciding") {
  // Half the fixes jump 15 m about (multipath in an urban canyon): no rotation explains 60 % of them.
  GnssHeadingAlignment align;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-15, 15);
  for (int k = 0; k < 40; ++k) {
    Eigen::Vector2d fix(0, k);
    if (k % 2 == 1) fix += Eigen::Vector2d(u(rng), u(rng));
    CHECK_FALSE(align.add(Eigen::Vector2d(k, 0), fix, 0.25 * Eigen::Matrix2d::Identity()));
  }
}

TEST_CASE("gnss heading: the stated yaw sigma matches the scatter over noise draws") {
  GnssHeadingOptions o;
  o.baseline_m = 40;
  int within_2_sigma = 0, runs = 300;
  double sum_sq = 0;
  for (int seed = 0; seed < runs; ++seed) {
    const auto [a, used] = run(160 * kDeg, 2.0, -1, static_cast<uint32_t>(seed), o);
    REQUIRE(a.has_value());
    const double z = wrapped(a->yaw - 160 * kDeg) / a->yaw_sigma;
    within_2_sigma += std::abs(z) < 2 ? 1 : 0;
    sum_sq += z * z;
  }
  // The track's own sigma (0.5 m, added to each fix's) makes the stated sigma slightly conservative.
  CHECK(within_2_sigma >= 0.93 * runs);
  CHECK(sum_sq / runs > 0.5);
  CHECK(sum_sq / runs < 1.3);
}

TEST_CASE("gnss heading: the least-squares fit minimizes the weighted residuals (brute force over the yaw)") {
  std::mt19937 rng(9);
  std::normal_distribution<double> n(0, 1.5);
  std::deque<GnssHeadingAlignment::Pair> pairs;
  for (const auto& p : track(50))
    pairs.push_back({p, rotated(-2.0, p) + Eigen::Vector2d(n(rng), 3 + n(rng)), 1.0 + (p.x() > 20)});
  const std::vector<bool> all(pairs.size(), true);
  const auto a = GnssHeadingAlignment::fit(pairs, all);
  REQUIRE(a.has_value());
  auto cost = [&](double yaw) {
    // For a given yaw the best translation is the weighted mean of fix - R track.
    Eigen::Vector2d t = Eigen::Vector2d::Zero();
    double sw = 0;
    for (const auto& p : pairs) t += p.weight * (p.fix - rotated(yaw, p.track)), sw += p.weight;
    t /= sw;
    double c = 0;
    for (const auto& p : pairs) c += p.weight * (p.fix - rotated(yaw, p.track) - t).squaredNorm();
    return c;
  };
  double best = 0, best_cost = 1e300;
  for (int k = -200000; k < 200000; ++k) {
    const double yaw = k * std::numbers::pi / 200000;
    if (const double c = cost(yaw); c < best_cost) best_cost = c, best = yaw;
  }
  CHECK(std::abs(wrapped(a->yaw - best)) < 2e-5);
  CHECK(cost(a->yaw) <= best_cost + 1e-9);
}
