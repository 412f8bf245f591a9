#pragma once
// Odometry-like motion for the latency benchmark: a planar unicycle driving at a constant speed with a slowly
// varying turn rate, sampled at a fixed period, as a wheel-odometry source would report it.
//   yaw rate   w(t) = w_max sin(2 pi t / turn_period)         (rad/s)
//   step k     delta_k = Exp([v dt, 0, 0, 0, 0, w(t_k) dt])   (body frame of the previous pose)
//   pose       T_k = T_{k-1} delta_k,  T_0 = identity
//   covariance P_k = Ad(delta_k^-1) P_{k-1} Ad(delta_k^-1)' + Q,  Q = diag(s_t^2 d, s_t^2 d, 0, 0, 0, s_r^2 d), d = v dt
// (the same propagation as convert/g2o_converter.cpp), Q also sent as the increment covariance.
// Times: utime_k = start_utime + k * period_us, strictly increasing.
#include "daemon/engine/events.hpp"
#include "estimators/lie/se3.hpp"

#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>

namespace sextant::bench {

struct OdometryTrackOptions {
  std::string source = "latency_body";
  int64_t start_utime = 0;
  int64_t period_us = 1000;         // 1 kHz
  double speed = 1.0;               // m/s
  double max_turn_rate = 0.4;       // rad/s
  double turn_period_s = 20.0;      // s
  double sigma_translation = 0.02;  // m per sqrt(m) travelled
  double sigma_rotation = 0.005;    // rad per sqrt(m) travelled
};

class OdometryTrack {
 public:
  explicit OdometryTrack(const OdometryTrackOptions& o) : o_(o) {
    const double d = o_.speed * static_cast<double>(o_.period_us) * 1e-6;
    q_.setZero();
    q_(0, 0) = q_(1, 1) = o_.sigma_translation * o_.sigma_translation * d;
    q_(5, 5) = o_.sigma_rotation * o_.sigma_rotation * d;
    covariance_ = q_;
  }

  /// w(t_k), rad/s.
  double turn_rate(int64_t k) const {
    const double t = static_cast<double>(k * o_.period_us) * 1e-6;
    return o_.max_turn_rate * std::sin(2.0 * std::numbers::pi * t / o_.turn_period_s);
  }
  const OdometryTrackOptions& options() const { return o_; }

  /// The odometry message of step k = the number of previous calls (k = 0 is the identity pose).
  engine::Odometry next() {
    if (k_ > 0) {
      const double dt = static_cast<double>(o_.period_us) * 1e-6;
      const double w = turn_rate(k_);
      Vector6d xi = Vector6d::Zero();
      xi(0) = o_.speed * dt;
      xi(5) = w * dt;
      const SE3 delta = SE3::exp(xi);
      const Matrix6d ad = delta.inverse().adjoint();
      covariance_ = ad * covariance_ * ad.transpose() + q_;
      covariance_ = (0.5 * (covariance_ + covariance_.transpose())).eval();
      pose_ = pose_ * delta;
    }
    engine::Odometry odo;
    odo.utime = o_.start_utime + k_ * o_.period_us;
    odo.source = o_.source;
    odo.planar = true;
    odo.pose.position = pose_.translation();
    odo.pose.orientation = pose_.rotation().quaternion();
    odo.covariance = covariance_;
    odo.increment_covariance = q_;
    ++k_;
    return odo;
  }

 private:
  OdometryTrackOptions o_;
  SE3 pose_;
  Matrix6d q_, covariance_;
  int64_t k_ = 0;
};

}  // namespace sextant::bench
