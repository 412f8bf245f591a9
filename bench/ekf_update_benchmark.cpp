// EKF-SLAM update time against the number of landmarks in the state (Google Benchmark).
// Targets: <= 20 us with 15 landmarks, <= 2 ms with 500.
#include "estimators/filter/planar_ekf.hpp"

#include <benchmark/benchmark.h>

#include <cmath>

namespace {

void BM_EkfSlamUpdate(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  sextant::filter::PlanarEkfOptions o;
  o.gate = 0;  // measure the update, never skip it
  sextant::filter::PlanarEkf ekf(o);
  ekf.initialize(sextant::SE2(0, 0, 0), Eigen::Matrix3d::Identity() * 1e-4);
  const Eigen::Matrix2d R = Eigen::Vector2d(0.01, 0.001).asDiagonal();
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * i / n;
    ekf.observe(i, 5.0 + (i % 7), a, R);  // augments the state with landmark i
  }
  int k = 0;
  for (auto _ : state) {
    const int id = k++ % n;
    const auto r = ekf.observe(id, 5.0 + (id % 7), 2 * M_PI * id / n, R);
    benchmark::DoNotOptimize(r);
  }
  state.counters["landmarks"] = n;
}
BENCHMARK(BM_EkfSlamUpdate)->Arg(15)->Arg(100)->Arg(500)->Unit(benchmark::kMicrosecond);

void BM_EkfPredict(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  sextant::filter::PlanarEkf ekf;
  ekf.initialize(sextant::SE2(0, 0, 0), Eigen::Matrix3d::Identity() * 1e-4);
  for (int i = 0; i < n; ++i) ekf.observe(i, 5.0, 2 * M_PI * i / n, Eigen::Matrix2d::Identity() * 0.01);
  const Eigen::Matrix3d Q = Eigen::Matrix3d::Identity() * 1e-6;
  for (auto _ : state) ekf.predict(sextant::SE2(0.01, 0, 0.001), Q);
}
BENCHMARK(BM_EkfPredict)->Arg(15)->Arg(500)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
