#include "convert/tum_converter.hpp"

#include "daemon/engine/dead_reckoning_stage.hpp"
#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/lcm_log.hpp"
#include "estimators/lie/planar_axes.hpp"
#include "eval/trajectory_io.hpp"

#include <sextant/truth_t.hpp>

#include <cmath>
#include <random>

namespace sextant::tools {

TumConversion convert_tum(const std::string& gt_tum, const std::string& out_lcm, const TumConversionOptions& o) {
  const auto gt = read_tum(gt_tum);
  if (gt.size() < 2) throw std::runtime_error(gt_tum + ": fewer than two poses");
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  runtime::LogWriter out(out_lcm);
  TumConversion result;
  const auto active = pose_axes(o.planar);
  SE3 odom;
  engine::Matrix6 cov = engine::Matrix6::Zero();
  for (int i : active) cov(i, i) = 1e-8;
  SE3 previous;
  int64_t last_utime = 0, seq = 0, seq_truth = 0;
  const auto frame_period_us =
      o.frame_rate_hz > 0 ? static_cast<int64_t>(std::llround(1e6 / o.frame_rate_hz)) : int64_t{0};
  int64_t next_frame = 0;
  for (size_t k = 0; k < gt.size(); ++k) {
    const int64_t utime = static_cast<int64_t>(std::llround(gt[k].t * 1e6));
    if (utime <= last_utime) continue;  // two stamps within a microsecond: keep the first
    last_utime = utime;
    const SE3 truth(gt[k].pose.orientation.normalized(), gt[k].pose.position);
    sextant::truth_t t{};
    t.utime = utime;
    t.sender = "sextant-convert";
    t.seq = seq_truth++;
    t.kind = "robot";
    t.source = o.source;
    for (int i = 0; i < 3; ++i) t.position[i] = truth.translation()[i];
    const auto& qt = truth.rotation().quaternion();
    t.orientation[0] = qt.w(), t.orientation[1] = qt.x(), t.orientation[2] = qt.y(), t.orientation[3] = qt.z();
    // A camera frame: the first sample at or after each frame time (every sample when frame_rate_hz <= 0).
    if (k > 0 && utime < next_frame) {
      out.write(utime, "GROUND_TRUTH", t);
      continue;
    }
    next_frame = (k == 0 ? utime : next_frame) + frame_period_us;
    // The first frame time after `utime`, in one step (a gap of 9e12 s used to take 10^14 iterations).
    if (frame_period_us > 0 && next_frame <= utime)
      next_frame += ((utime - next_frame) / frame_period_us + 1) * frame_period_us;
    engine::Matrix6 q = engine::Matrix6::Zero();
    if (k == 0) {
      odom = truth;
      for (int i : active) q(i, i) = 1e-8;
    } else {
      const SE3 delta_true = previous.between(truth);
      const double dist = delta_true.translation().norm();
      const double angle = delta_true.rotation().log().norm();
      const double min_var = o.min_sigma * o.min_sigma;
      const double var_t = o.trans_noise * o.trans_noise * dist + min_var;
      const double var_r = o.rot_noise * o.rot_noise * angle + min_var;
      Vector6d eta = Vector6d::Zero();
      for (int i : active) {
        q(i, i) = i < 3 ? var_t : var_r;
        eta[i] = std::sqrt(q(i, i)) * normal(rng);
      }
      eta.head<3>() += o.scale_drift * delta_true.translation();
      eta[5] += o.yaw_drift * dist;
      const SE3 delta = delta_true * SE3::exp(eta);
      cov = engine::DeadReckoningStage::propagate(cov, delta, q);
      odom = odom * delta;
    }
    previous = truth;
    engine::Odometry odo;
    odo.utime = utime;
    odo.source = o.source;
    odo.planar = o.planar;
    odo.pose.position = odom.translation();
    odo.pose.orientation = odom.rotation().quaternion();
    odo.covariance = cov;
    odo.increment_covariance = q;
    out.write(utime, "ODOMETRY", runtime::to_message(odo, "sextant-convert", seq++));
    out.write(utime, "GROUND_TRUTH", t);
    ++result.odometry;
  }
  out.flush();
  return result;
}

}  // namespace sextant::tools
