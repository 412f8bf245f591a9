#include "daemon/engine/dead_reckoning_stage.hpp"

#include <Eigen/Eigenvalues>

namespace sextant::engine {
namespace {

SE3 to_se3(const Pose& p) { return SE3(p.orientation, p.position); }

Pose to_pose(const SE3& x) {
  Pose p;
  p.position = x.translation();
  p.orientation = x.rotation().quaternion();
  return p;
}

// Nearest positive semi-definite matrix (Higham 1988): symmetrize and clamp negative eigenvalues to zero.
Matrix6 nearest_psd(const Matrix6& m) {
  const Matrix6 s = 0.5 * (m + m.transpose());
  Eigen::SelfAdjointEigenSolver<Matrix6> eig(s);
  const Eigen::Matrix<double, 6, 1> ev = eig.eigenvalues().cwiseMax(0.0);
  return eig.eigenvectors() * ev.asDiagonal() * eig.eigenvectors().transpose();
}

// The tangent components a planar source uses: x, y, yaw.
constexpr int kPlanarActive[] = {0, 1, 5};

}  // namespace

Matrix6 DeadReckoningStage::propagate(const Matrix6& previous, const SE3& increment, const Matrix6& q) {
  const Matrix6 ad = increment.inverse().adjoint();
  const Matrix6 p = ad * previous * ad.transpose() + q;
  return 0.5 * (p + p.transpose());
}

void DeadReckoningStage::handle(const Event& e, const Emit& emit) {
  const auto& odo = std::get<Odometry>(e);
  ++processed_;
  const SE3 odom = to_se3(odo.pose);
  auto [it, first] = tracks_.try_emplace(odo.source);
  Track& t = it->second;
  if (first) {
    t.map_pose = odom;
    t.covariance = odo.covariance;
  } else {
    if (odo.utime <= t.utime) return;  // intake guarantees increasing utime per source; keep the invariant local too
    if (static_cast<double>(odo.utime - t.utime) * 1e-6 > config_.max_gap_s) ++gaps_;
    const SE3 increment = t.last_odom.between(odom);
    Matrix6 q = odo.increment_covariance
                    ? *odo.increment_covariance
                    : nearest_psd(odo.covariance - propagate(t.last_odom_covariance, increment, Matrix6::Zero()));
    if (odo.planar) {
      for (int i : kPlanarActive) q(i, i) += config_.min_increment_variance;
    } else {
      q.diagonal().array() += config_.min_increment_variance;
    }
    t.map_pose = t.map_pose * increment;
    t.covariance = propagate(t.covariance, increment, q);
  }
  t.utime = odo.utime;
  t.last_odom = odom;
  t.last_odom_covariance = odo.covariance;

  FusedPose out;
  out.utime = odo.utime;
  out.source = odo.source;
  out.estimator = "dead_reckoning";
  out.planar = odo.planar;
  out.pose = to_pose(t.map_pose);
  out.covariance = t.covariance;
  emit(out);
}

Counters DeadReckoningStage::counters() const {
  return {{"odometry_processed", processed_}, {"odometry_gaps", gaps_},
          {"sources", static_cast<int64_t>(tracks_.size())}};
}

}  // namespace sextant::engine
