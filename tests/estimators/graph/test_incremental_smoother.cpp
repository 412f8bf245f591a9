// Incremental smoother: after every update the estimate equals a batch Gauss-Newton solve of the same graph (chi2 to
// 0.1 %, poses to millimetres), whatever the insertion order; large loop corrections relinearize; the gauge, bad
// input and an undetermined variable are handled; a wrong loop closure does not bend the map under DCS.
#include "estimators/graph/g2o_io.hpp"
#include "estimators/graph/incremental_smoother.hpp"
#include "estimators/graph/optimizer.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <random>

using namespace sextant;
using namespace sextant::graph;

namespace {

struct Edge {
  int i, j;
  SE3 z;
};

struct SyntheticGraph {
  bool planar = true;
  std::vector<SE3> truth;
  std::vector<Edge> edges;  // odometry in order, then loop closures interleaved where they happen
};

// A robot driving `laps` laps of a rounded square (planar) or a rising helix (3-D); odometry with noise, and a loop
// closure from each pose to the pose at the same place one lap earlier.
SyntheticGraph make_graph(bool planar, int laps, int per_lap, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  SyntheticGraph g;
  g.planar = planar;
  for (int k = 0; k < laps * per_lap; ++k) {
    const double a = 2 * M_PI * k / per_lap;
    const Eigen::Vector3d p(10 * std::cos(a), 10 * std::sin(a), planar ? 0.0 : 0.2 * k / per_lap);
    Eigen::Matrix3d R = Eigen::AngleAxisd(a + M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    if (!planar) R = R * Eigen::AngleAxisd(0.05 * std::sin(a), Eigen::Vector3d::UnitX()).toRotationMatrix();
    g.truth.push_back(SE3(SO3(Eigen::Quaterniond(R)), p));
  }
  auto noisy = [&](const SE3& z, double st, double sr) {
    Vector6d xi;
    for (int k = 0; k < 3; ++k) xi[k] = st * n(rng);
    for (int k = 3; k < 6; ++k) xi[k] = sr * n(rng);
    if (planar) xi[2] = xi[3] = xi[4] = 0;
    return z * SE3::exp(xi);
  };
  for (int k = 1; k < laps * per_lap; ++k) {
    g.edges.push_back({k - 1, k, noisy(g.truth[k - 1].inverse() * g.truth[k], 0.05, 0.01)});
    if (k >= per_lap)
      g.edges.push_back({k - per_lap, k, noisy(g.truth[k - per_lap].inverse() * g.truth[k], 0.05, 0.01)});
  }
  return g;
}

std::unique_ptr<Factor> make_factor(const SyntheticGraph& g, const Edge& e, int vi, int vj) {
  if (g.planar)
    return std::make_unique<RelativePoseFactor>(vi, vj, SE2::from_se3(e.z),
                                                Eigen::Matrix3d(Eigen::Vector3d(400, 400, 10000).asDiagonal()));
  Vector6d d;
  d << 400, 400, 400, 10000, 10000, 10000;
  return std::make_unique<RelativePoseFactor>(vi, vj, e.z, Matrix6d(d.asDiagonal()));
}

Variable pose_variable(bool planar, int64_t id, const SE3& x) {
  Variable v;
  v.id = id;
  v.kind = planar ? VariableKind::kPose2 : VariableKind::kPose3;
  if (planar)
    v.pose2 = SE2::from_se3(x);
  else
    v.pose3 = x;
  return v;
}

// The initial value of pose `end` of edge e when it enters: the edge composed with the other end's estimate in `s`
// (identity when the other end is not in yet).
SE3 initial_pose(const IncrementalSmoother& s, const std::vector<int>& index, const Edge& e, int end) {
  const int other = end == e.i ? e.j : e.i;
  if (index[static_cast<size_t>(other)] < 0) return SE3();
  const SE3 known = s.graph().variables()[static_cast<size_t>(index[static_cast<size_t>(other)])].as_se3();
  return end == e.j ? known * e.z : known * e.z.inverse();
}

// make_graph's lap of 40 poses with a heading bias of 0.01 rad on every odometry edge: closed at once by a loop edge,
// the correction moves every pose past the relinearization thresholds.
SyntheticGraph biased_lap(bool planar) {
  SyntheticGraph g = make_graph(planar, 1, 40, 3);
  for (auto& e : g.edges) e.z = e.z * SE3::exp((Vector6d() << 0, 0, 0, 0, 0, 0.01).finished());
  return g;
}

// Feeds the first `poses` poses of g's lap to `s`, one per update, each initialized by composing its odometry edge
// (g.edges[k - 1], from pose k - 1 to k) with the previous pose's initial value; `batch` (empty), when given, gets the
// same variables and factors.  Returns the poses' indices in `s`.
std::vector<int> feed_odometry(const SyntheticGraph& g, int poses, IncrementalSmoother& s,
                               FactorGraph* batch = nullptr) {
  std::vector<int> idx;
  SE3 x;
  for (int k = 0; k < poses; ++k) {
    if (k > 0) x = x * g.edges[static_cast<size_t>(k - 1)].z;
    idx.push_back(s.add_variable(pose_variable(g.planar, k, x)));
    if (batch != nullptr) batch->add_variable(pose_variable(g.planar, k, x));
    if (k > 0) {
      const Edge& e = g.edges[static_cast<size_t>(k - 1)];
      s.add_factor(make_factor(g, e, idx[static_cast<size_t>(k - 1)], idx[static_cast<size_t>(k)]));
      if (batch != nullptr) batch->add_factor(make_factor(g, e, k - 1, k));
    }
    REQUIRE(s.update().ok);
  }
  return idx;
}

// Feeds the edges in `order` (a pose enters when first referenced, initialized by composing the edge with the known
// end), updating after each edge; every `check_every` updates compares with a batch solve of the same graph from the
// same start.  Returns the number of comparisons made.
int run_and_compare(const SyntheticGraph& g, const std::vector<size_t>& order, int check_every,
                    IncrementalOptions opt = {}) {
  IncrementalSmoother s(opt);
  FactorGraph start;  // the same variables with the initial values the smoother got, and the same factors
  std::vector<int> index(g.truth.size(), -1);
  int compared = 0, updates = 0;
  for (size_t k : order) {
    const Edge& e = g.edges[k];
    for (int end : {e.i, e.j}) {
      if (index[static_cast<size_t>(end)] >= 0) continue;
      const SE3 init = initial_pose(s, index, e, end);
      index[static_cast<size_t>(end)] = s.add_variable(pose_variable(g.planar, end, init));
      start.add_variable(pose_variable(g.planar, end, init));
    }
    s.add_factor(make_factor(g, e, index[static_cast<size_t>(e.i)], index[static_cast<size_t>(e.j)]));
    start.add_factor(make_factor(g, e, index[static_cast<size_t>(e.i)], index[static_cast<size_t>(e.j)]));
    const IncrementalStatus st = s.update();
    REQUIRE_MESSAGE(st.ok, st.message);
    // The smoother's cached chi2 (recomputed only for factors whose variables moved) equals a full evaluation.
    CHECK(s.chi2() == doctest::Approx(s.graph().chi2()).epsilon(1e-12));
    if (++updates % check_every != 0 && k != order.back()) continue;
    // The batch reference: the same variables from the same start, the same factors (rebuilt from their data).
    FactorGraph b2;
    for (const auto& v : start.variables()) b2.add_variable(v);
    for (size_t q = 0; q < start.factors().size(); ++q) {
      const auto* rf = dynamic_cast<const RelativePoseFactor*>(start.factors()[q].get());
      REQUIRE(rf != nullptr);
      if (g.planar)
        b2.add_factor(std::make_unique<RelativePoseFactor>(rf->variables()[0], rf->variables()[1], rf->measurement2(),
                                                           Eigen::Matrix3d(rf->information())));
      else
        b2.add_factor(std::make_unique<RelativePoseFactor>(rf->variables()[0], rf->variables()[1], rf->measurement3(),
                                                           Matrix6d(rf->information())));
    }
    OptimizerOptions bo;
    bo.relative_tolerance = 1e-10;
    const auto sum = optimize(b2, bo);
    REQUIRE(sum.usable());
    const double inc = s.chi2(), ref = sum.final_chi2;
    // 0.1 % of chi2, and an absolute 1e-3 for graphs whose optimum has chi2 ~ 0 (a tree: no loop yet).
    CHECK_MESSAGE(inc <= ref * 1.001 + 1e-3, "update " << updates << ": incremental chi2 " << inc << " batch " << ref);
    double worst = 0;
    for (size_t v = 0; v < b2.variables().size(); ++v)
      worst = std::max(
          worst, (s.graph().variables()[v].as_se3().translation() - b2.variables()[v].as_se3().translation()).norm());
    CHECK_MESSAGE(worst < 0.02, "update " << updates << ": a pose differs from batch by " << worst << " m");
    ++compared;
  }
  return compared;
}

}  // namespace

TEST_CASE("incremental equals batch after every update, planar and 3-D, in file order") {
  for (bool planar : {true, false}) {
    CAPTURE(planar);
    const SyntheticGraph g = make_graph(planar, 3, 24, 7);
    std::vector<size_t> order(g.edges.size());
    std::iota(order.begin(), order.end(), 0);
    CHECK(run_and_compare(g, order, 1) == static_cast<int>(order.size()));
  }
}

TEST_CASE("incremental equals batch for random insertion orders that keep the graph connected") {
  for (uint64_t seed : {1u, 2u, 3u}) {
    for (bool planar : {true, false}) {
      CAPTURE(seed);
      CAPTURE(planar);
      const SyntheticGraph g = make_graph(planar, 3, 16, seed);
      // A random order in which every edge touches a pose already in the graph (pose 0 first).
      std::mt19937_64 rng(seed);
      std::vector<char> have(g.truth.size(), 0), used(g.edges.size(), 0);
      have[0] = 1;
      std::vector<size_t> order;
      while (order.size() < g.edges.size()) {
        std::vector<size_t> candidates;
        for (size_t k = 0; k < g.edges.size(); ++k)
          if (!used[k] && (have[static_cast<size_t>(g.edges[k].i)] || have[static_cast<size_t>(g.edges[k].j)]))
            candidates.push_back(k);
        const size_t k = candidates[rng() % candidates.size()];
        used[k] = 1;
        have[static_cast<size_t>(g.edges[k].i)] = have[static_cast<size_t>(g.edges[k].j)] = 1;
        order.push_back(k);
      }
      // Edge 0 must come first for pose 0 to be the gauge: put it there.
      std::iter_swap(order.begin(), std::find(order.begin(), order.end(), size_t{0}));
      CHECK(run_and_compare(g, order, 3) > 0);
    }
  }
}

TEST_CASE("a reordering spread over updates equals batch, and gives the same estimates however its slices fall") {
  // A low fill ratio makes the loop closures trigger reorderings often; each is spread over three updates.
  IncrementalOptions opt;
  opt.refill_ratio = 1.05;
  opt.reorder_spread = 3;
  opt.reorder_spread_above = 0;
  for (bool planar : {true, false}) {
    CAPTURE(planar);
    const SyntheticGraph g = make_graph(planar, 3, 24, 7);
    std::vector<size_t> order(g.edges.size());
    std::iota(order.begin(), order.end(), 0);
    CHECK(run_and_compare(g, order, 1, opt) == static_cast<int>(order.size()));

    // No time for it in any update (all the work at the update that puts it in place) against all the time in the
    // world (all the work in the update that begins it): the same numbers after every update.
    IncrementalOptions lazy = opt, eager = opt;
    lazy.reorder_slice_ms = 0.0;
    eager.reorder_slice_ms = 1e9;
    IncrementalSmoother a(lazy), b(eager);
    std::vector<int> ia(g.truth.size(), -1), ib(g.truth.size(), -1);
    int spread_seen = 0, installed = 0;
    for (const Edge& e : g.edges) {
      for (int end : {e.i, e.j}) {
        if (ia[static_cast<size_t>(end)] >= 0) continue;
        const SE3 init = initial_pose(a, ia, e, end);
        ia[static_cast<size_t>(end)] = a.add_variable(pose_variable(planar, end, init));
        ib[static_cast<size_t>(end)] = b.add_variable(pose_variable(planar, end, init));
      }
      a.add_factor(make_factor(g, e, ia[static_cast<size_t>(e.i)], ia[static_cast<size_t>(e.j)]));
      b.add_factor(make_factor(g, e, ib[static_cast<size_t>(e.i)], ib[static_cast<size_t>(e.j)]));
      const IncrementalStatus sa = a.update(), sb = b.update();
      REQUIRE(sa.ok);
      REQUIRE(sb.ok);
      CHECK(sa.rebuilt == sb.rebuilt);
      spread_seen += a.reordering() ? 1 : 0;
      installed += sa.rebuilt ? 1 : 0;
      for (size_t v = 0; v < a.graph().variables().size(); ++v) {
        const SE3 xa = a.graph().variables()[v].as_se3(), xb = b.graph().variables()[v].as_se3();
        REQUIRE(xa.translation() == xb.translation());
        REQUIRE(xa.rotation().quaternion().coeffs() == xb.rotation().quaternion().coeffs());
      }
    }
    CHECK(spread_seen > 0);
    CHECK(installed > 2);
    CHECK(a.rebuilds() == b.rebuilds());
  }
}

TEST_CASE("a long loop closed at once relinearizes, and a rebuild reorders without changing the estimate") {
  // One lap of 40 poses with a heading bias in the odometry, closed by one loop edge at the end: the correction
  // moves the poses by metres, far past the relinearization thresholds.
  SyntheticGraph g = biased_lap(true);
  g.edges.push_back({0, 39, g.truth[0].inverse() * g.truth[39]});
  std::vector<size_t> order(g.edges.size());
  std::iota(order.begin(), order.end(), 0);
  CHECK(run_and_compare(g, order, 1) == static_cast<int>(order.size()));

  IncrementalSmoother s;
  const std::vector<int> idx = feed_odometry(g, 40, s);
  s.add_factor(make_factor(g, g.edges.back(), idx[0], idx[39]));
  const IncrementalStatus st = s.update();
  REQUIRE(st.ok);
  CHECK((st.relinearized_variables > 0 || st.rebuilt));
  const double before = s.chi2();
  const auto rebuilt = s.rebuild();
  REQUIRE(rebuilt.ok);
  CHECK(s.chi2() == doctest::Approx(before).epsilon(1e-3));
}

TEST_CASE("a hub too heavy for the rank-update budget is relinearized by a rebuild, not by rank updates") {
  // Thirty poses on an arc (exact odometry), then a landmark seen from all of them, entered 2 m from where the
  // sightings put it: the first solve moves it far past the thresholds, the poses stay.  With an unlimited budget
  // its 30 sightings are relinearized by rank updates; with a budget this hub (30 factors) exceeds kHubRebuildAbove
  // times (relinearize_work 1), none is, the system is rebuilt instead (at once: a small system), and the answer is
  // the same.
  const Eigen::Vector2d landmark(5.0, 3.0);
  for (double budget : {1e12, 1.0}) {
    CAPTURE(budget);
    IncrementalOptions opt;
    opt.min_update_factors = opt.max_update_factors = 128;
    opt.relinearize_work = budget;
    IncrementalSmoother s(opt);
    std::vector<SE2> x;
    std::vector<int> idx;
    for (int k = 0; k < 30; ++k) {
      x.push_back(SE2(0.3 * k, 0.02 * k * k, 0.05 * k));
      idx.push_back(s.add_variable(pose_variable(true, k, x.back().to_se3())));
      if (k > 0)
        s.add_factor(std::make_unique<RelativePoseFactor>(idx[static_cast<size_t>(k - 1)], idx[static_cast<size_t>(k)],
                                                          x[static_cast<size_t>(k - 1)].inverse() * x.back(),
                                                          Eigen::Matrix3d::Identity() * 100));
      REQUIRE(s.update().ok);
    }
    Variable point;
    point.id = 100;
    point.kind = VariableKind::kPoint2;
    point.point = Eigen::Vector3d(landmark.x() + 2.0, landmark.y(), 0);
    const int p = s.add_variable(point);
    for (int k = 0; k < 30; ++k)
      s.add_factor(std::make_unique<PointObservationFactor>(
          idx[static_cast<size_t>(k)], p, PointObservationFactor::Model::kPosition,
          Eigen::VectorXd(x[static_cast<size_t>(k)].inverse().act(landmark)), Eigen::MatrixXd::Identity(2, 2) * 100));
    int most_by_rank_updates = 0, rebuilt = 0;
    for (int k = 0; k < 4; ++k) {
      const IncrementalStatus st = s.update();
      REQUIRE(st.ok);
      most_by_rank_updates = std::max(most_by_rank_updates, st.relinearized_factors);
      rebuilt += st.rebuilt ? 1 : 0;
    }
    if (budget > 1) {
      CHECK(most_by_rank_updates >= 30);
    } else {
      CHECK(most_by_rank_updates == 0);
      CHECK(rebuilt > 0);
    }
    s.refresh_estimate();
    CHECK(s.graph().variables()[static_cast<size_t>(p)].point.head<2>().isApprox(landmark, 1e-6));
    CHECK(s.chi2() < 1e-12);
  }
}

TEST_CASE("a variable over the relinearization budget alone waits for its turn, cheaper ones do not") {
  // The biased lap closed at once (as above): the correction moves every pose past the thresholds.  With a budget
  // no single variable fits (relinearize_work 1), each is relinearized alone and only at every
  // heavy_relinearize_every-th update; with an unlimited one, at every update until none has moved.  Either way the
  // estimate ends at the batch solution of the same factors.
  SyntheticGraph g = biased_lap(true);
  g.edges.push_back({0, 39, g.truth[0].inverse() * g.truth[39]});
  for (const auto& [budget, every] : {std::pair{1.0, 3}, std::pair{1.0, 1}, std::pair{1e12, 3}}) {
    CAPTURE(budget);
    CAPTURE(every);
    IncrementalOptions opt;
    opt.min_update_factors = opt.max_update_factors = 1000;  // relinearized by rank updates, never by a rebuild
    opt.relinearize_work = budget;
    opt.heavy_relinearize_every = every;
    IncrementalSmoother s(opt);
    FactorGraph batch;
    const std::vector<int> idx = feed_odometry(g, 40, s, &batch);
    s.add_factor(make_factor(g, g.edges.back(), idx[0], idx[39]));
    batch.add_factor(make_factor(g, g.edges.back(), 0, 39));
    std::vector<int> relinearized;  // variables relinearized per update, from the one that closed the loop
    for (int k = 0; k < 150; ++k) {
      const IncrementalStatus st = s.update();
      REQUIRE(st.ok);
      CHECK(!st.rebuilt);
      relinearized.push_back(st.relinearized_variables);
    }
    int updates_that_did = 0;
    for (size_t k = 0; k < relinearized.size(); ++k) {
      if (relinearized[k] == 0) continue;
      ++updates_that_did;
      if (budget < 10) {
        CHECK(relinearized[k] <= opt.relinearization_passes);  // one variable per round
        for (size_t j = k + 1; j < std::min(relinearized.size(), k + static_cast<size_t>(every)); ++j)
          CHECK(relinearized[j] == 0);  // the next turn is `every` updates later
      }
    }
    CHECK(updates_that_did > 0);
    if (budget > 10) CHECK(relinearized[0] > 10);  // cheap: all at once, at once
    s.refresh_estimate();
    OptimizerOptions bo;
    bo.relative_tolerance = 1e-12;
    REQUIRE(optimize(batch, bo).usable());
    // Within what the thresholds leave (a step under 0.1 keeps its linearization point): 4e-5 here, the same in all.
    CHECK(s.chi2() == doctest::Approx(batch.chi2()).epsilon(1e-4));
  }
}

TEST_CASE("a rebuild for relinearization spread over updates ends at the batch solution of the same factors") {
  // The biased lap closed at once, as above: the correction moves every pose past the thresholds, more factors than
  // rank updates take (update limit 4), so the rebuild is begun and spread over the next updates; relinearization
  // waits for it, and by rank updates is held to one variable per round (relinearize_work tiny) before and after.
  SyntheticGraph g = biased_lap(false);
  IncrementalOptions opt;
  opt.reorder_spread_above = 0;
  opt.reorder_spread = 3;
  opt.min_update_factors = opt.max_update_factors = 4;
  opt.relinearize_work = 1.0;
  IncrementalSmoother s(opt);
  FactorGraph batch;
  const std::vector<int> idx = feed_odometry(g, 40, s, &batch);
  const Edge loop{0, 39, g.truth[0].inverse() * g.truth[39]};
  s.add_factor(make_factor(g, loop, idx[0], idx[39]));
  batch.add_factor(make_factor(g, loop, 0, 39));
  const int rebuilds_before = s.rebuilds();
  IncrementalStatus st = s.update();
  REQUIRE(st.ok);
  CHECK_FALSE(st.rebuilt);  // not in this update: begun, and spread
  CHECK(s.reordering());
  bool installed = false;
  int waited = 0;
  for (int k = 0; k < 40; ++k) {  // updates with nothing new: the spread rebuild lands
    const bool under_way = s.reordering();
    st = s.update();
    REQUIRE(st.ok);
    if (under_way && !st.rebuilt) {  // relinearization waits for the new linearization
      ++waited;
      CHECK(st.relinearized_variables == 0);
    }
    installed = installed || st.rebuilt;
  }
  CHECK(installed);
  CHECK(waited >= 2);
  CHECK(s.rebuilds() > rebuilds_before);
  s.refresh_estimate();
  OptimizerOptions bo;
  bo.relative_tolerance = 1e-12;
  const auto ref = optimize(batch, bo);
  REQUIRE(ref.usable());
  CHECK(s.chi2() == doctest::Approx(ref.final_chi2).epsilon(1e-6));
  for (size_t v = 0; v < batch.variables().size(); ++v) {
    CHECK((s.graph().variables()[v].as_se3().translation() - batch.variables()[v].as_se3().translation()).norm() <
          1e-3);
    CHECK((s.graph().variables()[v].as_se3().rotation().inverse() * batch.variables()[v].as_se3().rotation())
              .log()
              .norm() < 1e-4);
  }
}

TEST_CASE("a first factorization spread over updates: the estimates stand until it lands, then the batch solution") {
  // A smoother built whole from a solved graph (as a lifelong thinning builds its successor): the first two laps'
  // factors at the batch solution of them.  Spread, its first factorization is built over the next `reorder_spread`
  // updates, during which nothing is solved and the third lap's first poses and edges wait; then it is put in place
  // and they enter.  After the rest of the third lap, it and a smoother given the same factors one update at a time
  // from the start end at the batch solution of all of them.
  for (bool planar : {true, false}) {
    CAPTURE(planar);
    const SyntheticGraph g = make_graph(planar, 3, 24, 11);
    const int first = 2 * 24;  // poses of the first two laps
    std::vector<size_t> early, late;
    for (size_t k = 0; k < g.edges.size(); ++k)
      (std::max(g.edges[k].i, g.edges[k].j) < first ? early : late).push_back(k);

    // The first two laps, solved in batch from dead reckoning.
    std::vector<SE3> dead_reckoning(static_cast<size_t>(first));
    for (size_t k : early)
      if (g.edges[k].j == g.edges[k].i + 1)
        dead_reckoning[static_cast<size_t>(g.edges[k].j)] =
            dead_reckoning[static_cast<size_t>(g.edges[k].i)] * g.edges[k].z;
    FactorGraph solved;
    for (int k = 0; k < first; ++k)
      solved.add_variable(pose_variable(planar, k, dead_reckoning[static_cast<size_t>(k)]));
    for (size_t k : early) solved.add_factor(make_factor(g, g.edges[k], g.edges[k].i, g.edges[k].j));
    OptimizerOptions solve_tight;
    solve_tight.relative_tolerance = 1e-12;
    REQUIRE(optimize(solved, solve_tight).usable());

    IncrementalOptions opt;
    opt.reorder_spread = 4;
    IncrementalSmoother spread(opt), at_once(opt);
    for (IncrementalSmoother* s : {&spread, &at_once}) {
      for (const auto& v : solved.variables()) s->add_variable(v);
      for (size_t k : early) s->add_factor(make_factor(g, g.edges[k], g.edges[k].i, g.edges[k].j));
    }
    REQUIRE(spread.begin_spread_build());
    CHECK_FALSE(spread.begin_spread_build());  // one at a time
    CHECK(spread.reordering());
    CHECK_FALSE(spread.factorized());
    int building = 0, landed = 0;
    for (size_t k : late) {
      const Edge& e = g.edges[k];
      for (IncrementalSmoother* s : {&spread, &at_once}) {
        if (s->index_of(e.j) < 0)  // a new pose: the edge composed with the other end's estimate
          s->add_variable(
              pose_variable(planar, e.j, s->graph().variables()[static_cast<size_t>(s->index_of(e.i))].as_se3() * e.z));
        s->add_factor(make_factor(g, e, s->index_of(e.i), s->index_of(e.j)));
      }
      const auto before = spread.graph().variables();
      const IncrementalStatus a = spread.update(), b = at_once.update();
      REQUIRE(a.ok);
      REQUIRE(b.ok);
      if (a.building) {
        ++building;
        CHECK(a.solves == 0);
        CHECK_FALSE(spread.factorized());
        CHECK(spread.marginal_covariance(first - 1).size() == 0);  // no factorization yet
        for (size_t v = 0; v < before.size(); ++v) {               // nothing moves
          REQUIRE(spread.graph().variables()[v].as_se3().translation() == before[v].as_se3().translation());
        }
      } else {
        landed += a.rebuilt ? 1 : 0;
        CHECK(spread.factorized());
      }
    }
    CHECK(building == opt.reorder_spread);
    CHECK(landed >= 1);
    CHECK(spread.rebuilds() >= 1);

    FactorGraph batch;  // everything, from the same values the smoothers hold now
    for (const auto& v : spread.graph().variables()) batch.add_variable(v);
    for (const auto& f : spread.graph().factors()) batch.add_factor(f->clone());
    const auto ref = optimize(batch, solve_tight);
    REQUIRE(ref.usable());
    spread.refresh_estimate();
    at_once.refresh_estimate();
    for (IncrementalSmoother* s : {&spread, &at_once}) {
      // Within what fluid relinearization leaves (steps under 0.1 m / 0.1 rad keep their linearization point):
      // 3-D, the spread one 3.7e-6 above batch, the other 7e-7 (planar: both 1e-9).
      CAPTURE(s == &spread);
      CHECK(s->chi2() == doctest::Approx(ref.final_chi2).epsilon(1e-5));
      for (size_t v = 0; v < batch.variables().size(); ++v)
        CHECK((s->graph().variables()[v].as_se3().translation() - batch.variables()[v].as_se3().translation()).norm() <
              1e-3);
    }
  }
}

TEST_CASE("bad input: unknown variables, NaN, non-positive-definite information, duplicate ids") {
  IncrementalSmoother s;
  const int a = s.add_variable(pose_variable(true, 0, SE3()));
  CHECK_THROWS_AS(s.add_variable(pose_variable(true, 0, SE3())), std::invalid_argument);
  Variable nan = pose_variable(true, 5, SE3());
  nan.pose2 = SE2(std::nan(""), 0, 0);
  CHECK_THROWS_AS(s.add_variable(nan), std::invalid_argument);
  CHECK_THROWS_AS(s.add_factor(std::make_unique<RelativePoseFactor>(a, 7, SE2(1, 0, 0), Eigen::Matrix3d::Identity())),
                  std::invalid_argument);
  const int b = s.add_variable(pose_variable(true, 1, SE3()));
  Eigen::Matrix3d bad = Eigen::Matrix3d::Identity();
  bad(2, 2) = -1;
  try {
    s.add_factor(std::make_unique<RelativePoseFactor>(a, b, SE2(1, 0, 0), bad));
    FAIL("a non-positive-definite information was accepted");
  } catch (const std::invalid_argument& e) {
    CHECK(std::string(e.what()).find("not positive definite") != std::string::npos);
  }
  s.add_factor(std::make_unique<RelativePoseFactor>(a, b, SE2(1, 0, 0), Eigen::Matrix3d::Identity()));
  REQUIRE(s.update().ok);
  CHECK(s.graph().variables()[static_cast<size_t>(b)].pose2.translation().x() == doctest::Approx(1.0));
}

TEST_CASE("a variable no factor determines waits, a component not tied to the gauge is reported by id") {
  IncrementalSmoother s;
  const int a = s.add_variable(pose_variable(true, 0, SE3()));
  const int p = [&] {
    Variable v;
    v.id = 100;
    v.kind = VariableKind::kPoint2;
    v.point = Eigen::Vector3d(3, 1, 0);
    return s.add_variable(v);
  }();
  // One bearing determines only one direction of a 2-D point: the point waits.
  s.add_factor(std::make_unique<PointObservationFactor>(a, p, PointObservationFactor::Model::kBearing,
                                                        Eigen::VectorXd::Constant(1, std::atan2(1.0, 3.0)),
                                                        Eigen::MatrixXd::Identity(1, 1) * 100));
  auto st = s.update();
  REQUIRE(st.ok);
  CHECK(st.deferred_variables == 1);
  // A second pose and a second bearing triangulate it.
  const int b = s.add_variable(pose_variable(true, 1, SE3(SO3(), Eigen::Vector3d(2, 0, 0))));
  s.add_factor(std::make_unique<RelativePoseFactor>(a, b, SE2(2, 0, 0), Eigen::Matrix3d::Identity() * 100));
  s.add_factor(std::make_unique<PointObservationFactor>(b, p, PointObservationFactor::Model::kBearing,
                                                        Eigen::VectorXd::Constant(1, std::atan2(1.0, 1.0)),
                                                        Eigen::MatrixXd::Identity(1, 1) * 100));
  st = s.update();
  REQUIRE(st.ok);
  CHECK(st.deferred_variables == 0);
  CHECK(s.graph().variables()[static_cast<size_t>(p)].point.head<2>().isApprox(Eigen::Vector2d(3, 1), 1e-6));
  // Two poses tied only to each other: the system is singular, and the status names one of them.
  const int c = s.add_variable(pose_variable(true, 50, SE3()));
  const int d = s.add_variable(pose_variable(true, 51, SE3()));
  s.add_factor(std::make_unique<RelativePoseFactor>(c, d, SE2(1, 0, 0), Eigen::Matrix3d::Identity()));
  st = s.update();
  CHECK_FALSE(st.ok);
  CHECK((st.message.find("variable 50") != std::string::npos || st.message.find("variable 51") != std::string::npos));
  CHECK(st.failure == SmootherFailure::kUnderdetermined);
  // The next update rebuilds, and fails the same way while the two are in the system and undetermined.
  st = s.update();
  CHECK_FALSE(st.ok);
  CHECK(st.failure == SmootherFailure::kUnderdetermined);
}

// How far a confident but wrong loop closure (pose 5 claimed 8 m from where pose 30 really is) moves the map of a
// DCS smoother whose options' width is `options_width`, the loop added with its own `loop_width` when given; and the
// loop's robust weight at the end.
struct WrongLoopEffect {
  double worst_shift = 0, loop_weight = 0, loop_chi2 = 0;
};
WrongLoopEffect wrong_loop_effect(double options_width, std::optional<double> loop_width) {
  const SyntheticGraph g = make_graph(true, 2, 20, 11);
  IncrementalOptions opt;
  opt.kernel = RobustKernel::kDcs;
  opt.kernel_width = options_width;
  // A rebuild iterates until no step exceeds the relinearization thresholds, so two smoothers with different
  // histories agree to about those thresholds (0.1 by default: 0.03-0.17 m apart here, by the number of relinearization
  // rounds per update); tighter ones leave only the wrong loop's pull to measure.
  opt.relinearize_translation = opt.relinearize_rotation = 0.01;
  IncrementalSmoother s(opt), clean(opt);  // the same kernel, without the wrong loop
  std::vector<int> idx(g.truth.size(), -1), idx_clean(g.truth.size(), -1);
  for (const Edge& e : g.edges) {
    for (auto* sm : {&s, &clean}) {
      auto& ix = sm == &s ? idx : idx_clean;
      for (const int end : {e.i, e.j})
        if (ix[static_cast<size_t>(end)] < 0)
          ix[static_cast<size_t>(end)] = sm->add_variable(pose_variable(true, end, initial_pose(*sm, ix, e, end)));
      sm->add_factor(make_factor(g, e, ix[static_cast<size_t>(e.i)], ix[static_cast<size_t>(e.j)]));
      REQUIRE(sm->update().ok);
    }
  }
  s.add_factor(make_factor(g, Edge{5, 30, g.truth[5].inverse() * g.truth[30] * SE3(SO3(), Eigen::Vector3d(8, 0, 0))},
                           idx[5], idx[30]),
               true, loop_width);
  REQUIRE(s.update().ok);
  // Compared at convergence (a rebuild iterates Gauss-Newton to the end), so that what differs is the wrong loop's
  // pull and not the two smoothers' different relinearization histories.
  REQUIRE(s.rebuild().ok);
  REQUIRE(clean.rebuild().ok);
  WrongLoopEffect r;
  for (size_t v = 0; v < g.truth.size(); ++v)
    r.worst_shift =
        std::max(r.worst_shift, (s.graph().variables()[static_cast<size_t>(idx[v])].as_se3().translation() -
                                 clean.graph().variables()[static_cast<size_t>(idx_clean[v])].as_se3().translation())
                                    .norm());
  const size_t loop = s.graph().factors().size() - 1;
  const Factor& f = *s.graph().factors()[loop];
  Eigen::VectorXd e(f.residual_dim());
  f.error(s.linearization_point(), e);
  r.loop_chi2 = e.dot(f.information() * e);
  r.loop_weight = s.robust_weight_of(loop);
  return r;
}

TEST_CASE(
    "with DCS a wrong loop closure does not bend the incremental map, a factor's own kernel width applies to it") {
  // DCS weight (Agarwal et al. 2013): min(1, 2 phi / (phi + chi2))^2, computed here from the loop's own residual.
  const auto dcs = [](double phi, double chi2) { return std::pow(std::min(1.0, 2 * phi / (phi + chi2)), 2); };
  const WrongLoopEffect narrow = wrong_loop_effect(1.0, std::nullopt);
  CHECK(narrow.worst_shift < 1e-3);
  CHECK(narrow.loop_weight == doctest::Approx(dcs(1.0, narrow.loop_chi2)).epsilon(1e-12));
  // So wide a kernel is no kernel: the wrong loop bends the map ...
  const WrongLoopEffect wide = wrong_loop_effect(1e12, std::nullopt);
  CHECK(wide.worst_shift > 1.0);
  CHECK(wide.loop_weight == doctest::Approx(1.0));
  // ... unless the loop brings its own width, which overrides the options' for it alone.
  const WrongLoopEffect own = wrong_loop_effect(1e12, 1.0);
  CHECK(own.worst_shift < 1e-3);
  CHECK(own.loop_weight == doctest::Approx(dcs(1.0, own.loop_chi2)).epsilon(1e-12));
  CHECK(own.loop_weight < 1e-3);
  // A width that is not a positive finite number is refused, naming the factor.
  IncrementalSmoother s;
  const int a = s.add_variable(pose_variable(true, 0, SE3()));
  const int b = s.add_variable(pose_variable(true, 1, SE3()));
  for (const double bad : {0.0, -1.0, std::nan(""), std::numeric_limits<double>::infinity()})
    CHECK_THROWS_WITH_AS(
        s.add_factor(std::make_unique<RelativePoseFactor>(a, b, SE2(1, 0, 0), Eigen::Matrix3d::Identity()), true, bad),
        doctest::Contains("factor 0: kernel width"), std::invalid_argument);
}

TEST_CASE("marginal covariance: the block of the inverse of the dense normal equations, for every variable") {
  // The reference: H = sum J' Omega J over all factors at the linearization point, assembled densely here from the
  // factors' own Jacobians (fixed variables left out), inverted by Eigen.  The smoother's marginal walks only one path
  // of its factor's elimination tree; both must give the same block, old variables (long paths) as well as new ones.
  for (bool planar : {true, false}) {
    CAPTURE(planar);
    const SyntheticGraph g = make_graph(planar, 2, 16, 3);
    IncrementalSmoother s;
    std::vector<int> index(g.truth.size(), -1);
    Variable first = pose_variable(planar, 0, g.truth[0]);
    first.fixed = true;
    index[0] = s.add_variable(first);
    for (const Edge& e : g.edges) {
      for (int end : {e.i, e.j})
        if (index[static_cast<size_t>(end)] < 0)
          index[static_cast<size_t>(end)] = s.add_variable(pose_variable(planar, end, initial_pose(s, index, e, end)));
      s.add_factor(make_factor(g, e, index[static_cast<size_t>(e.i)], index[static_cast<size_t>(e.j)]), false);
      REQUIRE(s.update().ok);
    }
    const auto& lin = s.linearization_point();
    std::vector<int> col(lin.size(), -1);
    int n = 0;
    for (size_t v = 0; v < lin.size(); ++v)
      if (!lin[v].fixed) col[v] = n, n += lin[v].dim();
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(n, n);
    for (const auto& f : s.graph().factors()) {
      Linearization l = f->make_linearization(lin);
      f->linearize(lin, l);
      const auto& vs = f->variables();
      for (size_t a = 0; a < vs.size(); ++a)
        for (size_t b = 0; b < vs.size(); ++b) {
          const int ca = col[static_cast<size_t>(vs[a])], cb = col[static_cast<size_t>(vs[b])];
          if (ca < 0 || cb < 0) continue;
          H.block(ca, cb, l.jacobians[a].cols(), l.jacobians[b].cols()) +=
              l.jacobians[a].transpose() * f->information() * l.jacobians[b];
        }
    }
    const Eigen::MatrixXd P = H.inverse();
    double worst = 0;
    for (size_t v = 0; v < lin.size(); ++v) {
      const Eigen::MatrixXd m = s.marginal_covariance(static_cast<int>(v));
      if (lin[v].fixed) {
        CHECK(m.size() == 0);
        continue;
      }
      const int d = lin[v].dim();
      const Eigen::MatrixXd ref = P.block(col[v], col[v], d, d);
      REQUIRE(m.rows() == d);
      worst = std::max(worst, (m - ref).norm() / ref.norm());
    }
    CHECK(worst < 1e-8);
  }
}

namespace {

// Feeds every edge of `g` in file order to `s`, one update per edge (poses initialized by composing the edge), and
// calls after_update(k, status) after update k (1, 2, ...).
template <class AfterUpdate>
void feed_edges(const SyntheticGraph& g, IncrementalSmoother& s, AfterUpdate&& after_update) {
  std::vector<int> index(g.truth.size(), -1);
  int64_t k = 0;
  for (const Edge& e : g.edges) {
    for (int end : {e.i, e.j})
      if (index[static_cast<size_t>(end)] < 0)
        index[static_cast<size_t>(end)] = s.add_variable(pose_variable(g.planar, end, initial_pose(s, index, e, end)));
    s.add_factor(make_factor(g, e, index[static_cast<size_t>(e.i)], index[static_cast<size_t>(e.j)]));
    after_update(++k, s.update());
  }
}

// Gauss-Newton to its fixed point: a rebuild stops once no step exceeds the relinearization thresholds, a few more
// take the remaining quadratic convergence.
void converge(IncrementalSmoother& s) {
  for (int i = 0; i < 3; ++i) REQUIRE(s.rebuild().ok);
}

}  // namespace

TEST_CASE(
    "a CHOLMOD failure injected in the middle of a run is reported, and the next update recovers the same answer") {
  for (bool planar : {true, false}) {
    CAPTURE(planar);
    const SyntheticGraph g = make_graph(planar, 3, 24, 7);
    IncrementalSmoother clean;
    feed_edges(g, clean, [](int64_t k, const IncrementalStatus& st) {
      REQUIRE_MESSAGE(st.ok, "update " << k << ": " << st.message);
    });
    const double clean_incremental_chi2 = clean.chi2();
    converge(clean);
    // Update 1 is a rebuild (the numeric factorization fails), 40 and 100 add their edge by rank updates.
    for (int64_t fault_at : {1, 40, 100}) {
      CAPTURE(fault_at);
      IncrementalOptions opt;
      opt.fail_factorization_at_update = fault_at;
      IncrementalSmoother s(opt);
      int failed = 0, recovered = 0;
      feed_edges(g, s, [&](int64_t k, const IncrementalStatus& st) {
        if (k == fault_at + 1) {
          CHECK(st.rebuilt);  // the update after the failure builds the factorization again
          recovered += st.ok ? 1 : 0;
        }
        if (k != fault_at) {
          REQUIRE_MESSAGE(st.ok, "update " << k << ": " << st.message);
          return;
        }
        ++failed;
        CHECK_FALSE(st.ok);
        CHECK(st.failure == SmootherFailure::kFactorization);
        CHECK(st.message.find("CHOLMOD") != std::string::npos);
        CHECK(s.factor_nonzeros() == 0);  // the factorization was dropped
        CHECK(s.marginal_covariance(1).size() == 0);
      });
      CHECK(failed == 1);
      CHECK(recovered == 1);
      CHECK(s.graph().factors().size() == g.edges.size());
      // The incremental answer is close to the uninjected run's (their relinearization histories differ) ...
      CHECK(s.chi2() == doctest::Approx(clean_incremental_chi2).epsilon(0.01));
      // ... and at convergence the same.
      converge(s);
      CHECK(s.chi2() == doctest::Approx(clean.chi2()).epsilon(1e-12));
      double worst = 0;
      for (size_t v = 0; v < g.truth.size(); ++v)
        worst = std::max(worst, (s.graph().variables()[v].as_se3().translation() -
                                 clean.graph().variables()[v].as_se3().translation())
                                    .norm());
      CHECK(worst < 1e-8);  // nanometres: the fixed point to rounding
    }
  }
}
TEST_CASE("the gauge: the first pose is held fixed unless a variable is fixed or a factor is a prior") {
  for (bool with_prior : {false, true}) {
    CAPTURE(with_prior);
    IncrementalSmoother s;
    const int a = s.add_variable(pose_variable(true, 0, SE3()));
    const int b = s.add_variable(pose_variable(true, 1, SE3()));
    s.add_factor(std::make_unique<RelativePoseFactor>(a, b, SE2(1, 0, 0), Eigen::Matrix3d::Identity()));
    if (with_prior) s.add_factor(std::make_unique<PosePriorFactor>(a, SE2(5, 0, 0), Eigen::Matrix3d::Identity()));
    CHECK(s.graph().has_gauge() == with_prior);
    REQUIRE(s.update().ok);
    CHECK(s.linearization_point()[static_cast<size_t>(a)].fixed == !with_prior);
    CHECK(s.dimension() == (with_prior ? 6 : 3));
    // With the prior the map frame is the prior's: pose 0 at x = 5, pose 1 one metre on.
    CHECK(s.graph().variables()[static_cast<size_t>(b)].pose2.translation().x() ==
          doctest::Approx(with_prior ? 6.0 : 1.0));
  }
}
