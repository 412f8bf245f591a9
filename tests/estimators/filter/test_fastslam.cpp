// FastSLAM 2.0: low-variance resampling statistics and N_eff, the copy-on-write landmark map (isolation, sharing
// after resampling, persistence against a reference), the improved proposal against an independent joint EKF
// update and against the paper's information form, determinism for a seed, a simulated run far better than dead
// reckoning (SLAM with ids, localization, unknown ids), spurious sightings, and refusal of bad input.
#include "estimators/filter/fastslam.hpp"
#include "estimators/filter/kalman_update.hpp"
#include "estimators/filter/low_variance_resampling.hpp"
#include "estimators/filter/planar_ekf.hpp"

#include <doctest/doctest.h>

#include <Eigen/Cholesky>

#include <cmath>
#include <map>
#include <random>
#include <set>

using namespace sextant;
using namespace sextant::filter;

TEST_CASE("fastslam: low-variance resampling reproduces the weights") {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> U(0, 1);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<double> w(37);
    double sum = 0;
    for (double& x : w) sum += (x = std::pow(U(rng), 3));
    for (double& x : w) x /= sum;
    const int N = 500;
    const auto idx = low_variance_resample(w, N, U(rng));
    REQUIRE(idx.size() == static_cast<size_t>(N));
    CHECK(std::is_sorted(idx.begin(), idx.end()));
    std::vector<int> copies(w.size(), 0);
    for (int i : idx) ++copies[static_cast<size_t>(i)];
    // Systematic resampling: every particle is copied floor(N w) or ceil(N w) times (up to rounding of the sums).
    for (size_t i = 0; i < w.size(); ++i) {
      CHECK(copies[i] >= std::floor(N * w[i] - 1e-9));
      CHECK(copies[i] <= std::ceil(N * w[i] + 1e-9));
    }
  }
  // Unbiased: averaged over u, the copies are N w exactly.
  const std::vector<double> w = {0.1, 0.25, 0.05, 0.6};
  std::vector<double> mean(4, 0);
  const int reps = 2000, N = 7;
  for (int r = 0; r < reps; ++r)
    for (int i : low_variance_resample(w, N, (r + 0.5) / reps)) mean[static_cast<size_t>(i)] += 1.0 / reps;
  for (size_t i = 0; i < 4; ++i) CHECK(mean[i] == doctest::Approx(N * w[i]).epsilon(1e-3));
  // u at the ends of [0, 1) and a zero weight at the end are never drawn past.
  CHECK(low_variance_resample({0.5, 0.5, 0.0}, 4, 0.999999) == std::vector<int>{0, 0, 1, 1});
  CHECK(low_variance_resample({0.0, 1.0}, 3, 0.0) == std::vector<int>{1, 1, 1});
}

TEST_CASE("fastslam: effective sample size and log-weight normalization") {
  CHECK(effective_sample_size(std::vector<double>(50, 0.02)) == doctest::Approx(50));
  CHECK(effective_sample_size({1, 0, 0, 0}) == doctest::Approx(1));
  CHECK(effective_sample_size({0.5, 0.5, 0, 0}) == doctest::Approx(2));
  std::vector<double> w;
  // exp(-1000) underflows: the normalization subtracts the largest log-weight first.
  CHECK(normalize_log_weights({-1000, -1000 + std::log(3.0), -INFINITY, NAN}, w));
  CHECK(w[0] == doctest::Approx(0.25));
  CHECK(w[1] == doctest::Approx(0.75));
  CHECK(w[2] == 0);
  CHECK(w[3] == 0);
  CHECK_FALSE(normalize_log_weights({NAN, -INFINITY}, w));
  CHECK(w[0] == doctest::Approx(0.5));
}

namespace {
MapLandmark landmark_at(double x, double y, int64_t id) {
  MapLandmark l;
  l.mean = {x, y};
  l.covariance = Eigen::Matrix2d::Identity() * 0.1;
  l.id = id;
  return l;
}
}  // namespace

TEST_CASE("fastslam: copy-on-write landmark map, a change in one copy is not seen by another") {
  LandmarkMapTree a;
  for (int i = 0; i < 10; ++i) CHECK(a.push_back(landmark_at(i, -i, 100 + i)) == i);
  CHECK(a.slots() == 10);
  LandmarkMapTree b = a;  // O(1): one root pointer
  for (int i = 0; i < 10; ++i) CHECK(a.shares_slot_with(b, i));
  const int64_t nodes_before = a.node_count();
  b.set(3, landmark_at(42, 42, 103));
  CHECK(a.find(3)->mean.x() == 3);
  CHECK(b.find(3)->mean.x() == 42);
  CHECK_FALSE(a.shares_slot_with(b, 3));
  for (int i = 0; i < 10; ++i)
    if (i != 3) CHECK(a.shares_slot_with(b, i));
  // Path copying: 16 slots -> depth 4, so one update creates 4 internal nodes and 1 leaf; the rest is shared.
  CHECK(b.node_count() == nodes_before);
  b.erase(5);
  CHECK(b.find(5) == nullptr);
  CHECK(a.find(5) != nullptr);
  CHECK(b.find(99) == nullptr);
  CHECK(b.find(-1) == nullptr);
  // Growing past the capacity keeps the old slots (the old tree becomes the left subtree).
  LandmarkMapTree c = a;
  c.set(1000, landmark_at(7, 7, 7));
  CHECK(c.slots() == 1001);
  for (int i = 0; i < 10; ++i) CHECK(c.shares_slot_with(a, i));
  int visited = 0;
  c.for_each([&](int32_t slot, const MapLandmark& l) {
    CHECK(l.id == (slot == 1000 ? 7 : 100 + slot));
    ++visited;
  });
  CHECK(visited == 11);
}

TEST_CASE("fastslam: landmark map tree keeps every version, against std::map snapshots") {
  std::mt19937 rng(5);
  std::vector<LandmarkMapTree> versions(1);
  std::vector<std::map<int, double>> reference(1);
  for (int step = 0; step < 600; ++step) {
    const size_t from = std::uniform_int_distribution<size_t>(0, versions.size() - 1)(rng);
    LandmarkMapTree t = versions[from];
    std::map<int, double> r = reference[from];
    const int slot = std::uniform_int_distribution<int>(0, 70)(rng);
    if (rng() % 4 == 0) {
      t.erase(slot);
      r.erase(slot);
    } else {
      const double v = step;
      t.set(slot, landmark_at(v, 0, slot));
      r[slot] = v;
    }
    versions.push_back(t);
    reference.push_back(r);
  }
  for (size_t k = 0; k < versions.size(); ++k) {
    std::map<int, double> got;
    versions[k].for_each([&](int32_t s, const MapLandmark& l) { got[s] = l.mean.x(); });
    CHECK(got == reference[k]);
  }
}

TEST_CASE("fastslam: the improved proposal equals the pose marginal of a joint EKF update and the paper's form") {
  PoseGaussian g;
  g.mean << 1.0, -0.5, 0.3;
  Eigen::Matrix3d A;
  A << 0.3, 0.05, 0.02, 0, 0.2, -0.03, 0, 0, 0.1;
  g.covariance = A * A.transpose();
  const Eigen::Vector2d lm(4.0, 1.5);
  Eigen::Matrix2d S;
  S << 0.2, 0.05, 0.05, 0.1;
  Eigen::Matrix2d R;
  R << 0.04, 0.001, 0.001, 0.003;
  const Eigen::Vector2d z(3.3, 0.05);
  PoseGaussian got = g;
  const auto step = FastSlam::refine_proposal(got, lm, S, z, R);
  REQUIRE(step.has_value());

  // Independent: the EKF over [pose; landmark] with the block-diagonal prior, kalman_update, pose block.
  Eigen::Matrix<double, 2, 3> Hx;
  Eigen::Matrix2d Hl;
  const Eigen::Vector2d zhat = PlanarEkf::observation(g.mean, lm, &Hx, &Hl);
  Eigen::VectorXd x(5);
  x << g.mean, lm;
  Eigen::MatrixXd P = Eigen::MatrixXd::Zero(5, 5);
  P.topLeftCorner<3, 3>() = g.covariance;
  P.bottomRightCorner<2, 2>() = S;
  Eigen::MatrixXd H(2, 5);
  H << Hx, Hl;
  Eigen::VectorXd nu = z - zhat;
  nu[1] = wrap_angle(nu[1]);
  const auto u = kalman_update(x, P, nu, H, R, 0);
  REQUIRE(u.accepted);
  CHECK((got.mean - x.head<3>()).norm() < 1e-12);
  CHECK((got.covariance - P.topLeftCorner<3, 3>()).norm() < 1e-12);
  CHECK(step->d2 == doctest::Approx(u.nis).epsilon(1e-12));

  // The paper's information form: Sigma_s = [G_s' Q^-1 G_s + P^-1]^-1, mu_s = s + Sigma_s G_s' Q^-1 (z - zhat).
  const Eigen::Matrix2d Qn = R + Hl * S * Hl.transpose();
  const Eigen::Matrix3d Sigma_s = (Hx.transpose() * Qn.inverse() * Hx + g.covariance.inverse()).inverse();
  const Eigen::Vector3d mu_s = g.mean + Sigma_s * Hx.transpose() * Qn.inverse() * Eigen::Vector2d(nu);
  CHECK((got.mean - mu_s).norm() < 1e-10);
  CHECK((got.covariance - Sigma_s).norm() < 1e-10);

  // The weight: log N(z - zhat; 0, L), L = G_s P G_s' + G_theta Sigma G_theta' + R.
  const Eigen::Matrix2d L = Hx * g.covariance * Hx.transpose() + Qn;
  const double expected = -0.5 * nu.dot(L.inverse() * nu) - std::log(2 * M_PI) - 0.5 * std::log(L.determinant());
  CHECK(step->log_likelihood == doctest::Approx(expected).epsilon(1e-12));

  // A degenerate geometry (the landmark on the robot) is refused.
  PoseGaussian same = g;
  CHECK_FALSE(FastSlam::refine_proposal(same, g.mean.head<2>(), S, z, R).has_value());
}

namespace {

/// A planar world: the robot drives a loop among landmarks; odometry with noise drawn from Q; sightings within
/// `range` metres and +-60 degrees.
struct World {
  std::vector<Eigen::Vector2d> landmarks;
  std::vector<SE2> truth;                            // pose after each step
  std::vector<SE2> odometry;                         // noisy increments
  std::vector<std::vector<RangeBearing>> sightings;  // after each step (possibly empty)
  Eigen::Matrix3d Q;
  Eigen::Matrix2d R;
};

World make_world(int steps, uint32_t seed, double range = 4.0, double odometry_noise = 1.0) {
  World w;
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0, 1);
  for (int i = 0; i < 16; ++i) {
    const double a = 2 * M_PI * i / 16;
    w.landmarks.push_back(Eigen::Vector2d(5 * std::cos(a), 5 * std::sin(a)) * (i % 2 ? 0.6 : 1.3));
  }
  w.Q = odometry_noise * odometry_noise * Eigen::Vector3d(0.02 * 0.02, 0.01 * 0.01, 0.02 * 0.02).asDiagonal();
  w.R = Eigen::Vector2d(0.05 * 0.05, 0.02 * 0.02).asDiagonal();
  const Eigen::LLT<Eigen::Matrix3d> q(w.Q);
  SE2 x(0, -4, 0);
  for (int k = 0; k < steps; ++k) {
    const SE2 d(0.1, 0, 0.1 / 4.0);  // a circle of radius 4
    x = x * d;
    w.truth.push_back(x);
    // Drawn in a fixed order (the order of a constructor's arguments is the compiler's: g++ and clang drew different
    // worlds), the last component first as g++ did.
    const double n3 = n(rng), n2 = n(rng), n1 = n(rng);
    const Eigen::Vector3d e = q.matrixL() * Eigen::Vector3d(n1, n2, n3);
    w.odometry.push_back(d * SE2(e[0], e[1], e[2]).inverse());  // the true motion is odometry (+) noise
    std::vector<RangeBearing> s;
    if (k % 2 == 0) {
      for (size_t i = 0; i < w.landmarks.size(); ++i) {
        const Eigen::Vector2d h = PlanarEkf::observation(
            Eigen::Vector3d(x.translation().x(), x.translation().y(), x.angle()), w.landmarks[i], nullptr, nullptr);
        if (h[0] > range || std::abs(h[1]) > M_PI / 3) continue;
        s.push_back({static_cast<int64_t>(i), h[0] + 0.05 * n(rng), wrap_angle(h[1] + 0.02 * n(rng)), w.R});
      }
    }
    w.sightings.push_back(s);
  }
  return w;
}

struct RunResult {
  double rmse_pf = 0, rmse_dr = 0;
  std::vector<Eigen::Vector3d> poses;
  FastSlam filter;
};

RunResult run(const World& w, FastSlamOptions o, bool known_map, bool drop_ids) {
  RunResult r{0, 0, {}, FastSlam(o)};
  if (known_map)
    for (size_t i = 0; i < w.landmarks.size(); ++i)
      r.filter.set_known_landmark(static_cast<int64_t>(i), w.landmarks[i]);
  r.filter.initialize(SE2(0, -4, 0), Eigen::Matrix3d::Identity() * 1e-6);
  SE2 dr(0, -4, 0);
  double e_pf = 0, e_dr = 0;
  for (size_t k = 0; k < w.truth.size(); ++k) {
    REQUIRE(r.filter.predict(w.odometry[k], w.Q));
    dr = dr * w.odometry[k];
    auto s = w.sightings[k];
    if (drop_ids)
      for (auto& x : s) x.id = -1;
    if (!s.empty()) r.filter.observe(s);
    const SE2 m = r.filter.mean_pose();
    r.poses.push_back({m.translation().x(), m.translation().y(), m.angle()});
    e_pf += (m.translation() - w.truth[k].translation()).squaredNorm();
    e_dr += (dr.translation() - w.truth[k].translation()).squaredNorm();
  }
  r.rmse_pf = std::sqrt(e_pf / w.truth.size());
  r.rmse_dr = std::sqrt(e_dr / w.truth.size());
  return r;
}

}  // namespace

TEST_CASE("fastslam: a simulated run, far below dead reckoning (SLAM with ids, localization, unknown ids)") {
  const World w = make_world(500, 2);  // two laps
  FastSlamOptions o;
  o.particles = 50;
  o.seed = 9;
  const auto slam = run(w, o, false, false);
  MESSAGE("SLAM: pf " << slam.rmse_pf << " m, dead reckoning " << slam.rmse_dr << " m, resamplings "
                      << slam.filter.resamplings());
  CHECK(slam.rmse_pf < 0.3 * slam.rmse_dr);
  CHECK(slam.filter.resamplings() > 0);
  // Landmark estimates near the truth (the map frame is the start pose, which is the true one here).
  const auto map = slam.filter.landmarks();
  int close = 0;
  for (const auto& [id, p] : map) close += (p - w.landmarks[static_cast<size_t>(id)]).norm() < 0.5;
  CHECK(close == static_cast<int>(map.size()));
  CHECK(map.size() >= 8);

  const auto loc = run(w, o, true, false);
  MESSAGE("localization: pf " << loc.rmse_pf << " m");
  CHECK(loc.rmse_pf < 0.2 * loc.rmse_dr);
  CHECK(loc.rmse_pf < 0.1);

  // Without ids, per-particle maximum-likelihood association closes the loop only while the drift stays within
  // the gate: with half the odometry noise (the full noise drifts 0.7 m in a lap, beyond the gate, and the loop
  // closure then duplicates landmarks instead).
  const World quieter = make_world(500, 2, 4.0, 0.5);
  const auto unk = run(quieter, o, false, true);
  MESSAGE("unknown ids: pf " << unk.rmse_pf << " m, dead reckoning " << unk.rmse_dr << " m, landmarks "
                             << unk.filter.landmarks().size());
  CHECK(unk.rmse_pf < 0.6 * unk.rmse_dr);
  CHECK(unk.filter.landmarks().size() <= quieter.landmarks.size());  // no duplicates among the confirmed ones
  CHECK(unk.filter.landmarks().size() >= 8);

  // The published covariance covers the particle spread and is symmetric positive definite.
  const Eigen::Matrix3d C = slam.filter.pose_covariance();
  CHECK((C - C.transpose()).norm() == 0);
  CHECK(Eigen::LLT<Eigen::Matrix3d>(C + 1e-15 * Eigen::Matrix3d::Identity()).info() == Eigen::Success);
}

TEST_CASE("fastslam: determinism for a seed") {
  const World w = make_world(120, 3);
  FastSlamOptions o;
  o.particles = 30;
  o.seed = 77;
  const auto a = run(w, o, false, true);
  const auto b = run(w, o, false, true);
  REQUIRE(a.poses.size() == b.poses.size());
  for (size_t k = 0; k < a.poses.size(); ++k) CHECK(a.poses[k] == b.poses[k]);  // bit for bit
  for (size_t i = 0; i < a.filter.particles().size(); ++i)
    CHECK(a.filter.particles()[i].pose.mean == b.filter.particles()[i].pose.mean);
  o.seed = 78;
  const auto c = run(w, o, false, true);
  CHECK(c.poses.back() != a.poses.back());
}

TEST_CASE("fastslam: resampling shares the maps of duplicated particles, a later update unshares one") {
  FastSlamOptions o;
  o.particles = 40;
  o.seed = 3;
  o.resample_threshold = 0;  // resample only when asked
  FastSlam f(o);
  f.set_known_landmark(7, {3, 1});  // absolute poses matter: the weights differ
  f.initialize(SE2(0, 0, 0), Eigen::Vector3d(0.05, 0.05, 0.01).asDiagonal());
  const Eigen::Matrix2d R = Eigen::Vector2d(0.01, 0.001).asDiagonal();
  f.observe({{1, 2.0, 0.1, R}, {2, 3.0, -0.2, R}, {7, 3.16, 0.32, R}});
  f.predict(SE2(0.2, 0, 0.05), Eigen::Vector3d(0.01, 0.01, 0.01).asDiagonal());
  const auto out = f.observe({{1, 1.8, 0.12, R}, {2, 2.8, -0.22, R}, {7, 2.97, 0.29, R}});
  CHECK_FALSE(out.resampled);
  CHECK(out.updated == 3);
  // Every particle updated its own landmarks: no sharing yet.
  const auto& before = f.particles();
  for (size_t i = 1; i < before.size(); ++i)
    CHECK_FALSE(before[i].identified.shares_slot_with(before[0].identified, 0));
  const double neff = f.effective_sample_size();
  CHECK(neff < o.particles);
  f.resample();
  CHECK(f.effective_sample_size() == doctest::Approx(o.particles));
  const auto& ps = f.particles();
  int shared_pairs = 0, distinct_parents = 0;
  for (size_t i = 0; i < ps.size(); ++i) {
    bool seen = false;
    for (size_t j = 0; j < ps.size(); ++j) {
      if (i == j) continue;
      const bool same_parent = ps[i].pose.mean == ps[j].pose.mean;
      CHECK(ps[i].identified.shares_slot_with(ps[j].identified, 0) == same_parent);
      CHECK(ps[i].identified.shares_slot_with(ps[j].identified, 1) == same_parent);
      if (same_parent) {
        ++shared_pairs;
        if (j < i) seen = true;
      }
    }
    distinct_parents += !seen;
  }
  CHECK(shared_pairs > 0);
  CHECK(distinct_parents < o.particles);
  // Copy-on-write after resampling: a duplicate that updates landmark 1 stops sharing it, keeps sharing landmark 2.
  FastSlam g = f;
  const Eigen::Vector2d old1 = g.particles()[0].identified.find(0)->mean;
  g.observe({{1, 1.7, 0.1, R}});
  CHECK(f.particles()[0].identified.find(0)->mean == old1);  // the copy of the filter is untouched
  CHECK_FALSE(g.particles()[0].identified.shares_slot_with(f.particles()[0].identified, 0));
  CHECK(g.particles()[0].identified.shares_slot_with(f.particles()[0].identified, 1));
}

TEST_CASE("fastslam: a spurious sighting without id stays tentative and is removed") {
  FastSlamOptions o;
  o.particles = 10;
  o.confirmations = 3;
  o.tentative_lifetime = 5;
  FastSlam f(o);
  f.initialize(SE2(0, 0, 0), Eigen::Matrix3d::Identity() * 1e-6);
  const Eigen::Matrix2d R = Eigen::Vector2d(0.01, 0.001).asDiagonal();
  // A real landmark seen every time at (3, 0); a spurious one once at (2, 2).
  auto out = f.observe({{-1, 3.0, 0.0, R}, {-1, std::sqrt(8.0), M_PI / 4, R}});
  CHECK(out.created == 2);
  for (int k = 0; k < 8; ++k) {
    out = f.observe({{-1, 3.0, 0.0, R}});
    CHECK(out.associated == 1);
    CHECK(out.created == 0);
  }
  const auto map = f.landmarks();
  REQUIRE(map.size() == 1);
  CHECK((map.begin()->second - Eigen::Vector2d(3, 0)).norm() < 0.05);
  for (const auto& p : f.particles()) {
    int n = 0;
    p.unidentified.for_each([&](int32_t, const MapLandmark&) { ++n; });
    CHECK(n == 1);
  }
}

TEST_CASE("fastslam: NaN, infinities, non-positive ranges and non-PD covariances are counted and refused") {
  FastSlamOptions o;
  o.particles = 20;
  FastSlam f(o);
  f.initialize(SE2(0, 0, 0), Eigen::Matrix3d::Identity() * 0.01);
  const Eigen::Matrix2d R = Eigen::Vector2d(0.01, 0.001).asDiagonal();
  f.observe({{1, 2.0, 0.1, R}});
  const auto before = f.particles();
  Eigen::Matrix2d not_pd;
  not_pd << 0.01, 0.02, 0.02, 0.01;  // indefinite
  Eigen::Matrix2d asymmetric;
  asymmetric << 0.01, 0.005, 0, 0.01;
  const auto out = f.observe({{1, NAN, 0.1, R},
                              {1, 2.0, INFINITY, R},
                              {-1, -1.0, 0.1, R},
                              {2, 0.0, 0.1, R},
                              {3, 2.0, 0.1, not_pd},
                              {4, 2.0, 0.1, asymmetric},
                              {5, 2.0, 0.1, Eigen::Matrix2d::Constant(NAN)}});
  CHECK(out.rejected == 7);
  CHECK(out.created == 0);
  CHECK_FALSE(out.resampled);
  CHECK_FALSE(f.predict(SE2(NAN, 0, 0), Eigen::Matrix3d::Identity()));
  CHECK_FALSE(f.predict(SE2(0.1, 0, 0), Eigen::Matrix3d::Constant(INFINITY)));
  CHECK_FALSE(f.predict(SE2(0.1, 0, 0), -Eigen::Matrix3d::Identity()));
  const auto& after = f.particles();
  for (size_t i = 0; i < after.size(); ++i) {
    CHECK(after[i].pose.mean == before[i].pose.mean);
    CHECK(after[i].pose.covariance == before[i].pose.covariance);
    CHECK(after[i].log_weight == before[i].log_weight);
    CHECK(after[i].identified.slots() == 1);
  }
  // Localization mode: an id outside the known map is unknown, not a new landmark.
  FastSlamOptions lo = o;
  lo.slam = false;
  FastSlam l(lo);
  l.set_known_landmark(6, {2, 0});
  l.initialize(SE2(0, 0, 0), Eigen::Matrix3d::Identity() * 0.01);
  const auto r = l.observe({{6, 2.0, 0.0, R}, {9, 2.0, 0.3, R}});
  CHECK(r.updated == 1);
  CHECK(r.unknown == 1);
  // A sighting far from the only landmark in every particle is gated.
  const auto gated = l.observe({{6, 7.0, 1.0, R}});
  CHECK(gated.gated == 1);
  CHECK(gated.updated == 0);
}
