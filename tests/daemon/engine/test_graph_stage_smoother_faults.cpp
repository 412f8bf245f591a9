// The graph stage when its smoother's factorization fails (CHOLMOD out of memory, injected through
// IncrementalOptions::fail_factorization_at_update): the failed update is counted, the stage keeps taking keyframes
// and loops and publishing, and its map ends where the map of a stage without the fault ends.
#include "daemon/engine/graph_stage.hpp"
#include "daemon/stage_counters.hpp"
#include "daemon/engine/pose_conversion.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

using namespace sextant;
using namespace sextant::engine;

using sextant::stage_counters::counter;

namespace {

// A planar robot on a circle of radius 10 m at 1 m/s (a lap in 62.8 s), odometry at 10 Hz with a heading random
// walk, and from the second lap on a loop closure every 2 s to the pose one lap earlier (the true relative pose).
std::vector<Event> circle_with_loops(double seconds, uint64_t seed) {
  auto truth = [](double t) {
    const double a = t / 10.0;
    return SE3(SO3(Eigen::Quaterniond(Eigen::AngleAxisd(a + M_PI / 2, Eigen::Vector3d::UnitZ()))),
               Eigen::Vector3d(10 * std::cos(a), 10 * std::sin(a), 0));
  };
  auto utime_of = [](int k) { return int64_t{1'000'000} + k * int64_t{100'000}; };
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0, 1);
  std::vector<Event> events;
  SE3 odom = truth(0);
  const int lap = static_cast<int>(std::lround(20 * M_PI * 10));  // odometry messages per lap
  for (int k = 0; k <= static_cast<int>(seconds * 10); ++k) {
    if (k > 0) {
      Vector6d xi = Vector6d::Zero();
      xi[0] = 0.01 * n(rng), xi[1] = 0.01 * n(rng), xi[5] = 0.006 * n(rng);
      odom = odom * truth(0.1 * (k - 1)).inverse() * truth(0.1 * k) * SE3::exp(xi);
    }
    Odometry o;
    o.utime = utime_of(k);
    o.source = "robot";
    o.planar = true;
    o.pose = to_pose(odom);
    Matrix6 inc = Matrix6::Zero();
    inc(0, 0) = inc(1, 1) = 1e-4, inc(5, 5) = 3.6e-5;
    o.increment_covariance = inc;
    events.emplace_back(o);
    if (k > lap && k % 20 == 0) {
      LoopClosure l;
      l.utime = o.utime;
      l.source = "robot";
      l.planar = true;
      l.utime_from = utime_of(k - lap);
      l.utime_to = o.utime;
      l.relative = to_pose(truth(0.1 * (k - lap)).inverse() * truth(0.1 * k));
      l.information = Matrix6::Identity() * 1e4;
      events.emplace_back(l);
    }
  }
  return events;
}

}  // namespace

TEST_CASE("graph stage: a failed factorization is counted, the stage goes on and ends with the same map") {
  const std::vector<Event> events = circle_with_loops(140, 4);
  GraphConfig config;
  config.keyframes.k1 = 1.0;
  config.propose_loops = false;
  GraphStage clean(config, std::make_shared<GraphCorrections>());
  for (int64_t fault_at : {1, 60, 120}) {  // the first update (a rebuild), one of the first lap, one with loops
    CAPTURE(fault_at);
    GraphConfig faulty_config = config;
    faulty_config.smoother.fail_factorization_at_update = fault_at;
    GraphStage faulty(faulty_config, std::make_shared<GraphCorrections>());
    std::vector<int64_t> published;  // TRAJECTORY times of the faulty stage
    const Emit record = [&](Output out) {
      if (auto* t = std::get_if<Trajectory>(&out)) published.push_back(t->utime);
    };
    const Emit ignore = [](Output) {};
    int64_t failed_at_utime = -1;
    for (const Event& e : events) {
      if (fault_at == 1) clean.handle(e, ignore);  // the reference, once
      faulty.handle(e, record);
      if (failed_at_utime < 0 && counter(faulty, "optimizer_failures") > 0) failed_at_utime = event_utime(e);
    }
    CHECK(counter(clean, "optimizer_failures") == 0);
    CHECK(counter(faulty, "optimizer_failures") == 1);
    REQUIRE(failed_at_utime > 0);
    CHECK(counter(faulty, "updates") == counter(clean, "updates"));
    CHECK(counter(faulty, "updates") > fault_at + 50);
    CHECK(counter(faulty, "keyframes") == counter(clean, "keyframes"));
    CHECK(counter(clean, "loops_accepted") > 20);
    CHECK(counter(faulty, "loops_accepted") == counter(clean, "loops_accepted"));
    // Publications go on after the failure, to the end of the run.
    REQUIRE(!published.empty());
    CHECK(published.back() > failed_at_utime + 30'000'000);
    // At convergence (recover() rebuilds the smoothers: Gauss-Newton until no step passes the relinearization
    // thresholds, a few times for the rest of its quadratic convergence) the two maps are the same.
    for (int i = 0; i < 3; ++i) {
      clean.recover(events.front());
      faulty.recover(events.front());
    }
    const auto a = clean.keyframes("robot"), b = faulty.keyframes("robot");
    REQUIRE(a.size() == b.size());
    double worst = 0;
    for (size_t k = 0; k < a.size(); ++k) {
      CHECK(a[k].utime == b[k].utime);
      worst = std::max(worst, (a[k].pose.position - b[k].pose.position).norm());
    }
    CHECK(worst < 1e-5);  // 10 micrometres: the loops' DCS weights converge linearly, not quadratically
  }
}
