// Cost per IMU sample of the inertial estimators (Google Benchmark), IMU at 1 kHz on one body.
// Targets: preintegration <= 1 us per sample, the error-state filter's prediction <= 10 us per sample.
// Peer in the same run: the plain world-frame integration of a sample (rotation, velocity, position; no
// covariance, no Jacobians), the least work any inertial estimator does per sample.
#include "estimators/inertial/error_state_ekf.hpp"
#include "estimators/inertial/imu_preintegration.hpp"
#include "estimators/inertial/lagged_eskf.hpp"

#include <benchmark/benchmark.h>

#include <Eigen/Geometry>

#include <cmath>
#include <vector>

namespace {

using namespace sextant::inertial;

constexpr double kDt = 1e-3;  // 1 kHz

// One second of a vehicle turning and accelerating, as an IMU sees it (body frame, gravity in the specific force).
std::vector<BodyImuSample> one_second() {
  std::vector<BodyImuSample> s(1000);
  for (size_t k = 0; k < s.size(); ++k) {
    const double t = static_cast<double>(k) * kDt;
    s[k].gyro = Eigen::Vector3d(0.05 * std::sin(3 * t), 0.04 * std::cos(2 * t), 0.3);
    s[k].accel = Eigen::Vector3d(0.5 * std::cos(t), 0.3, 9.81);
  }
  return s;
}

void BM_WorldFrameIntegration(benchmark::State& state) {
  const std::vector<BodyImuSample> s = one_second();
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d v = Eigen::Vector3d::Zero(), p = Eigen::Vector3d::Zero();
  const Eigen::Vector3d g(0, 0, -9.81);
  size_t k = 0;
  for (auto _ : state) {
    const BodyImuSample& x = s[k++ % s.size()];
    const Eigen::Vector3d a = R * x.accel + g;
    p += v * kDt + 0.5 * a * kDt * kDt;
    v += a * kDt;
    const double angle = x.gyro.norm() * kDt;
    R = R * Eigen::AngleAxisd(angle, x.gyro.normalized()).toRotationMatrix();
    benchmark::DoNotOptimize(p);
  }
}
BENCHMARK(BM_WorldFrameIntegration);

void BM_PreintegrationPerSample(benchmark::State& state) {
  const std::vector<BodyImuSample> s = one_second();
  ImuPreintegration pim;
  size_t k = 0;
  for (auto _ : state) {
    const BodyImuSample& x = s[k % s.size()];
    if (++k % s.size() == 0) pim.reset(ImuBias{});  // keyframes a second apart
    pim.integrate(x.gyro, x.accel, kDt);
    benchmark::DoNotOptimize(pim.covariance().data());
  }
}
BENCHMARK(BM_PreintegrationPerSample);

void BM_EskfPerImuSample(benchmark::State& state) {
  const std::vector<BodyImuSample> s = one_second();
  ErrorStateEkf f;
  f.initialize(0, EskfState{}, ErrorStateEkf::Matrix15::Identity() * 1e-2);
  size_t k = 0;
  for (auto _ : state) {
    const ImuResult r = f.add_imu(static_cast<double>(k) * kDt, s[k % s.size()]);
    ++k;
    benchmark::DoNotOptimize(r);
  }
}
BENCHMARK(BM_EskfPerImuSample);

// The updates that arrive between IMU samples (GNSS at 5 Hz, wheel odometry at 50 Hz): their own cost.
void BM_EskfGnssPositionUpdate(benchmark::State& state) {
  ErrorStateEkf f;
  f.initialize(0, EskfState{}, ErrorStateEkf::Matrix15::Identity() * 1e-2);
  f.add_imu(0, BodyImuSample{Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, 9.80665)});
  const Eigen::Vector3d lever(0.2, 0, 0.5);
  for (auto _ : state) {
    const auto r = f.update_gnss_position(Eigen::Vector3d(0.01, -0.02, 0.0), Eigen::Matrix3d::Identity(), lever);
    benchmark::DoNotOptimize(r);
  }
}
BENCHMARK(BM_EskfGnssPositionUpdate);

void BM_EskfWheelVelocityUpdate(benchmark::State& state) {
  ErrorStateEkf f;
  f.initialize(0, EskfState{}, ErrorStateEkf::Matrix15::Identity() * 1e-2);
  f.add_imu(0, BodyImuSample{Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, 9.80665)});
  for (auto _ : state) {
    const auto r =
        f.update_body_velocity(Eigen::Vector3d(0.01, 0, 0), Eigen::Matrix3d::Identity() * 1e-2, SensorMounting{});
    benchmark::DoNotOptimize(r);
  }
}
BENCHMARK(BM_EskfWheelVelocityUpdate);

// A GNSS fix arriving 100 ms after its stamp at 1 kHz IMU: the update plus the 100 samples re-applied after it.
// Each iteration: 200 IMU samples (0.2 s) and one fix 100 ms late, reported per fix.
void BM_LaggedEskfLateFix(benchmark::State& state) {
  const std::vector<BodyImuSample> s = one_second();
  LaggedEskf f(EskfOptions{}, 0.5);
  f.initialize(0, EskfState{}, ErrorStateEkf::Matrix15::Identity() * 1e-2);
  size_t k = 0;
  const auto fix = [](ErrorStateEkf& e) {
    return e.update_gnss_position(Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
  };
  for (auto _ : state) {
    for (int i = 0; i < 200; ++i, ++k) f.add_imu(static_cast<double>(k) * kDt, s[k % s.size()]);
    const auto r = f.add_measurement(static_cast<double>(k - 100) * kDt, fix);
    benchmark::DoNotOptimize(r);
  }
}
BENCHMARK(BM_LaggedEskfLateFix)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
