// The error-state filter with late measurements: GNSS fixes delivered 150 ms after their stamps give exactly the
// estimate of a filter that received every input in time order; the history stays bounded; a measurement older
// than the history is refused.
#include "estimators/inertial/lagged_eskf.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <vector>

using namespace sextant::inertial;

namespace {

struct Input {
  double t;
  bool imu;
  BodyImuSample sample;
  Eigen::Vector3d fix;
};

// 30 s at 200 Hz of a body turning and accelerating gently, IMU samples and GNSS fixes (5 Hz, stamped between two
// samples), in stamp order.
std::vector<Input> inputs() {
  std::mt19937 rng(3);
  std::normal_distribution<double> n;
  std::vector<Input> out;
  for (int k = 0; k < 30 * 200; ++k) {
    const double t = k * 0.005;
    BodyImuSample s;
    s.gyro = Eigen::Vector3d(0.02 * std::sin(t), 0.01, 0.2 * std::cos(0.1 * t)) +
             0.002 * Eigen::Vector3d(n(rng), n(rng), n(rng));
    s.accel = Eigen::Vector3d(0.3 * std::cos(0.5 * t), 0.1, 9.80665) + 0.02 * Eigen::Vector3d(n(rng), n(rng), n(rng));
    out.push_back({t, true, s, {}});
    if (k % 40 == 13)
      out.push_back({t + 0.0023,
                     false,
                     {},
                     Eigen::Vector3d(0.5 * t, 0.1 * t, 0) + 0.3 * Eigen::Vector3d(n(rng), n(rng), n(rng))});
  }
  return out;
}

LaggedEskf::Update gnss(const Eigen::Vector3d& fix) {
  return [fix](ErrorStateEkf& f) {
    return f.update_gnss_position(fix, Eigen::Matrix3d::Identity() * 0.09, Eigen::Vector3d(0.1, 0, 0.5));
  };
}

ErrorStateEkf::Matrix15 initial_covariance() {
  ErrorStateEkf::Matrix15 P = ErrorStateEkf::Matrix15::Identity() * 1e-2;
  P.block<3, 3>(9, 9) *= 0.1;
  P.block<3, 3>(12, 12) *= 0.01;
  return P;
}

}  // namespace

TEST_CASE("lagged ESKF: fixes 150 ms late give the in-order estimate exactly") {
  const std::vector<Input> in = inputs();
  // Reference: every input in stamp order, straight into the filter.
  ErrorStateEkf ref;
  ref.initialize(0, EskfState{}, initial_covariance());
  for (const Input& x : in) {
    if (x.imu) {
      ref.add_imu(x.t, x.sample);
    } else {
      REQUIRE(ref.propagate_to(x.t));
      gnss(x.fix)(ref);
    }
  }
  // The same inputs, each fix delivered after the IMU samples of the next 150 ms.
  LaggedEskf lag(EskfOptions{}, 0.5);
  lag.initialize(0, EskfState{}, initial_covariance());
  std::vector<Input> pending;
  size_t max_history = 0;
  int accepted = 0;
  for (const Input& x : in) {
    if (!x.imu) {
      pending.push_back(x);
      continue;
    }
    REQUIRE(lag.add_imu(x.t, x.sample) != ImuResult::out_of_order);
    while (!pending.empty() && pending.front().t + 0.15 <= x.t) {
      accepted += lag.add_measurement(pending.front().t, gnss(pending.front().fix)).accepted;
      pending.erase(pending.begin());
    }
    max_history = std::max(max_history, lag.history_size());
  }
  for (const Input& x : pending) accepted += lag.add_measurement(x.t, gnss(x.fix)).accepted;  // the last fix
  CHECK(accepted == 150);
  CHECK(lag.replayed() > 149 * 29);  // each fix re-applied the 30 samples after it
  const ErrorStateEkf& f = lag.filter();
  CHECK(f.time() == ref.time());
  CHECK(ErrorStateEkf::difference(f.state(), ref.state()).norm() < 1e-9);
  CHECK((f.covariance() - ref.covariance()).cwiseAbs().maxCoeff() < 1e-12);
  CHECK(max_history <= 0.5 * 200 + 4);  // bounded by the history length
}

TEST_CASE(
    "lagged ESKF: a measurement older than the history is refused, a fix ahead of the IMU is re-applied after it") {
  LaggedEskf lag(EskfOptions{}, 0.2);
  lag.initialize(0, EskfState{}, initial_covariance());
  BodyImuSample rest;
  rest.accel = Eigen::Vector3d(0, 0, 9.80665);
  CHECK(lag.add_measurement(0, gnss(Eigen::Vector3d::Zero())).reason == sextant::filter::UpdateReason::kTooOld);
  for (int k = 0; k <= 200; ++k) lag.add_imu(k * 0.005, rest);
  CHECK(lag.add_measurement(0.5, gnss(Eigen::Vector3d::Zero())).reason == sextant::filter::UpdateReason::kTooOld);
  CHECK(lag.add_measurement(0.95, gnss(Eigen::Vector3d(0.2, 0, 0))).accepted);
  // A fix stamped after the newest sample: applied at its stamp (the held sample carries the state there); the
  // samples that arrive later with earlier stamps go before it and it is applied again.
  CHECK(lag.add_measurement(1.012, gnss(Eigen::Vector3d(0.3, 0, 0))).accepted);
  CHECK(lag.add_imu(1.005, rest) == ImuResult::propagated);
  CHECK(lag.add_imu(1.010, rest) == ImuResult::propagated);
  CHECK(lag.filter().time() == doctest::Approx(1.012));
  CHECK(lag.add_imu(1.0, rest) == ImuResult::out_of_order);
  CHECK(lag.filter().state().p.x() > 0.1);
}
