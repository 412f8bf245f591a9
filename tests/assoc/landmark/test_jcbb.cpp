// Landmark association: JCBB against a brute-force search over every hypothesis on small random problems, a case
// where nearest neighbour is fooled by a correlated pose error and JCBB is not.
#include "assoc/landmark/jcbb.hpp"

#include <doctest/doctest.h>

#include <chrono>
#include <random>

using namespace sextant::assoc;

namespace {

// A linear world: state [robot x, y, landmark 1 x, y, ...]; a sighting measures landmark - robot.
struct World {
  int landmarks;
  Eigen::MatrixXd P;
  Eigen::VectorXd x;
  std::vector<Eigen::Vector2d> z;
  std::vector<Eigen::MatrixXd> R;

  AssociationProblem problem() const {
    AssociationProblem p;
    p.sightings = static_cast<int>(z.size());
    p.landmarks = landmarks;
    p.covariance = &P;
    p.noise = R;
    p.candidate = [this](int i, int j) -> std::optional<Candidate> {
      Candidate c;
      c.jacobian = Eigen::MatrixXd::Zero(2, P.rows());
      c.jacobian.block<2, 2>(0, 0) = -Eigen::Matrix2d::Identity();
      c.jacobian.block<2, 2>(0, 2 + 2 * j) = Eigen::Matrix2d::Identity();
      c.innovation = z[static_cast<size_t>(i)] - (x.segment<2>(2 + 2 * j) - x.head<2>());
      return c;
    };
    return p;
  }
};

// Every hypothesis whose prefixes all pass the joint test (JCBB's own criterion), the best by (pairs, -D2).
Hypothesis brute_force(const AssociationProblem& p) {
  Hypothesis h(static_cast<size_t>(p.sightings), -1), best = h;
  int best_pairs = -1;
  double best_d2 = 1e300;
  std::function<void(int, int)> go = [&](int i, int pairs) {
    if (i == p.sightings) {
      const double d2 = joint_distance(p, h);
      if (pairs > best_pairs || (pairs == best_pairs && d2 < best_d2)) best = h, best_pairs = pairs, best_d2 = d2;
      return;
    }
    go(i + 1, pairs);
    for (int j = 0; j < p.landmarks; ++j) {
      bool used = false;
      for (int k = 0; k < i; ++k) used = used || h[static_cast<size_t>(k)] == j;
      if (used || individual_distance(p, i, j) >= p.individual_gate) continue;
      h[static_cast<size_t>(i)] = j;
      int dim = 0;
      if (joint_distance(p, h, &dim) < chi2_quantile(dim, p.joint_gate_probability)) go(i + 1, pairs + 1);
      h[static_cast<size_t>(i)] = -1;
    }
  };
  go(0, 0);
  return best;
}

}  // namespace

TEST_CASE("JCBB finds the same best hypothesis as an exhaustive search on random small problems") {
  std::mt19937 rng(21);
  std::normal_distribution<double> n(0, 1);
  std::uniform_real_distribution<double> u(-3, 3);
  int agreements = 0, trials = 40;
  for (int t = 0; t < trials; ++t) {
    World w;
    w.landmarks = 4;
    const int dim = 2 + 2 * w.landmarks;
    Eigen::MatrixXd A = Eigen::MatrixXd::Random(dim, dim) * 0.3;
    w.P = A * A.transpose() + 0.05 * Eigen::MatrixXd::Identity(dim, dim);
    w.x = Eigen::VectorXd::Zero(dim);
    for (int j = 0; j < w.landmarks; ++j) w.x.segment<2>(2 + 2 * j) = Eigen::Vector2d(u(rng), u(rng));
    // Sightings of landmarks 0..2 (shuffled) plus a spurious one.
    std::vector<int> seen = {2, 0, 1};
    for (int j : seen) {
      w.z.push_back(w.x.segment<2>(2 + 2 * j) + Eigen::Vector2d(0.2 * n(rng), 0.2 * n(rng)));
      w.R.push_back(Eigen::Matrix2d::Identity() * 0.04);
    }
    w.z.push_back(Eigen::Vector2d(u(rng), u(rng)));
    w.R.push_back(Eigen::Matrix2d::Identity() * 0.04);
    const auto p = w.problem();
    const Hypothesis j = joint_compatibility_branch_and_bound(p), b = brute_force(p);
    CHECK(j == b);
    agreements += j == b;
  }
  CHECK(agreements == trials);
}

TEST_CASE("a common pose error fools nearest neighbour, not JCBB") {
  // Landmarks at x = 0 and x = 1; the robot believes it is at the origin but its x is uncertain (sigma 1 m):
  // both sightings appear shifted by +0.6 m.  Individually, sighting 0 (true landmark 0, seen at 0.6) is nearer
  // landmark 1; jointly, the shared shift explains both.
  World w;
  w.landmarks = 2;
  w.P = Eigen::MatrixXd::Identity(6, 6) * 1e-4;
  w.P(0, 0) = 1.0;
  w.x = Eigen::VectorXd::Zero(6);
  w.x.segment<2>(2) = Eigen::Vector2d(0, 0);
  w.x.segment<2>(4) = Eigen::Vector2d(1, 0);
  w.z = {Eigen::Vector2d(0.6, 0), Eigen::Vector2d(1.6, 0)};
  w.R = {Eigen::Matrix2d::Identity() * 0.01, Eigen::Matrix2d::Identity() * 0.01};
  // Seen from the robot, the landmark positions are (landmark - robot); the robot's true x is -0.6.
  const auto p = w.problem();
  const auto nn = nearest_neighbour(p);
  const auto jc = joint_compatibility_branch_and_bound(p);
  CHECK(nn[0] == 1);  // fooled
  CHECK(jc == Hypothesis{0, 1});
  CHECK(joint_distance(p, jc) < joint_distance(p, Hypothesis{1, -1}) + 1.0);
}

TEST_CASE("JCBB's work budget: a batch of thousands of sightings ends within it, with nearest neighbour's pairing") {
  // 300 landmarks on a grid 1 m apart, 2000 sightings of them (each landmark several times): every sighting is
  // compatible with several landmarks, so the exact search is hopeless.  The budget bounds the work and the answer
  // is nearest neighbour over the individually compatible pairs: sound (each pair passes the individual gate).
  World w;
  w.landmarks = 300;
  const int dim = 2 + 2 * w.landmarks;
  w.P = Eigen::MatrixXd::Identity(dim, dim) * 0.25;
  w.x = Eigen::VectorXd::Zero(dim);
  for (int j = 0; j < w.landmarks; ++j) w.x.segment<2>(2 + 2 * j) = Eigen::Vector2d(j % 20, j / 20);
  std::mt19937 rng(4);
  for (int i = 0; i < 2000; ++i) {
    const int j = static_cast<int>(rng() % 300);
    w.z.push_back(w.x.segment<2>(2 + 2 * j) + Eigen::Vector2d(0.05, -0.05));
    w.R.push_back(Eigen::Matrix2d::Identity() * 0.04);
  }
  AssociationProblem p = w.problem();
  // The same problem with sparse Jacobians (the robot's and the landmark's columns only).
  p.candidate = [&w](int i, int j) -> std::optional<Candidate> {
    Candidate c;
    c.jacobian.resize(2, 4);
    c.jacobian << -Eigen::Matrix2d::Identity(), Eigen::Matrix2d::Identity();
    c.columns = {0, 1, 2 + 2 * j, 3 + 2 * j};
    c.innovation = w.z[static_cast<size_t>(i)] - (w.x.segment<2>(2 + 2 * j) - w.x.head<2>());
    return c;
  };
  p.work_budget = 2e7;
  const auto t0 = std::chrono::steady_clock::now();
  const BoundedAssociation a = associate_bounded(p);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  CHECK(a.exhausted);
  CHECK(a.work <= p.work_budget * 1.01 + 1e5);
  CHECK(seconds < 2.0);
  // Every pair it makes passes the individual gate; those examined are paired as nearest neighbour pairs them.
  int paired = 0;
  for (int i = 0; i < p.sightings; ++i) {
    const int j = a.pairing[static_cast<size_t>(i)];
    if (i >= a.examined) CHECK(j == -1);
    if (j < 0) continue;
    ++paired;
    CHECK(individual_distance(p, i, j) < p.individual_gate);
  }
  CHECK(paired > 0);
  CHECK(a.examined > 0);
  CHECK(a.examined < p.sightings);
}

TEST_CASE("sparse and dense Jacobians give the same distances and the same JCBB answer") {
  World w;
  w.landmarks = 5;
  const int dim = 2 + 2 * w.landmarks;
  Eigen::MatrixXd A = Eigen::MatrixXd::Random(dim, dim) * 0.3;
  w.P = A * A.transpose() + 0.05 * Eigen::MatrixXd::Identity(dim, dim);
  w.x = Eigen::VectorXd::Zero(dim);
  for (int j = 0; j < w.landmarks; ++j) w.x.segment<2>(2 + 2 * j) = Eigen::Vector2d(1.5 * j, 0.5 * j);
  for (int j : {3, 1, 4}) {
    w.z.push_back(w.x.segment<2>(2 + 2 * j) + Eigen::Vector2d(0.1, -0.1));
    w.R.push_back(Eigen::Matrix2d::Identity() * 0.04);
  }
  const AssociationProblem dense = w.problem();
  AssociationProblem sparse = dense;
  sparse.candidate = [&w](int i, int j) -> std::optional<Candidate> {
    Candidate c;
    c.jacobian.resize(2, 4);
    c.jacobian << -Eigen::Matrix2d::Identity(), Eigen::Matrix2d::Identity();
    c.columns = {0, 1, 2 + 2 * j, 3 + 2 * j};
    c.innovation = w.z[static_cast<size_t>(i)] - (w.x.segment<2>(2 + 2 * j) - w.x.head<2>());
    return c;
  };
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < w.landmarks; ++j)
      CHECK(individual_distance(sparse, i, j) == doctest::Approx(individual_distance(dense, i, j)));
  const Hypothesis h{3, 1, 4};
  CHECK(joint_distance(sparse, h) == doctest::Approx(joint_distance(dense, h)));
  CHECK(joint_compatibility_branch_and_bound(sparse) == joint_compatibility_branch_and_bound(dense));
}
