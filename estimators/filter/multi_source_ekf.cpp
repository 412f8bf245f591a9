#include "estimators/filter/multi_source_ekf.hpp"

#include "estimators/spd_matrix.hpp"
#include "estimators/lie/lie_archive.hpp"

#include "estimators/filter/interpolated_prediction.hpp"

#include <stdexcept>

namespace sextant::filter {
namespace {

bool any(const std::array<bool, 6>& f, int from, int to) {
  for (int i = from; i < to; ++i)
    if (f[static_cast<size_t>(i)]) return true;
  return false;
}

}  // namespace

MultiSourceEkf::MultiSourceEkf(const PlanarEkfOptions& options, const Eigen::Matrix3d& initial_covariance,
                               std::map<std::string, OdometrySourceOptions> sources, double min_increment_variance)
    : options_(options), initial_covariance_(initial_covariance), min_variance_(min_increment_variance), ekf_(options) {
  validate(sources);
  for (const auto& [name, o] : sources) {
    sources_[name].options = o;
    counters_[name];
  }
}

void MultiSourceEkf::validate(const std::map<std::string, OdometrySourceOptions>& sources) {
  int predicting = 0;
  for (const auto& [name, o] : sources) {
    if (o.predict) {
      ++predicting;
      if (!(o.fuse[0] && o.fuse[1] && o.fuse[2]) || any(o.fuse, 3, 6))
        throw std::invalid_argument("odometry source '" + name +
                                    "' predicts: it must fuse x, y and yaw and no velocity");
    } else {
      if (!any(o.fuse, 0, 6)) throw std::invalid_argument("odometry source '" + name + "' fuses no component");
      if (o.differential && any(o.fuse, 0, 3) && any(o.fuse, 3, 6))
        throw std::invalid_argument("odometry source '" + name +
                                    "': a differential pose and velocities fuse the same motion twice");
    }
    if (o.gate < 0 || o.timeout_s < 0)
      throw std::invalid_argument("odometry source '" + name + "': negative gate or timeout");
  }
  if (predicting != 1)
    throw std::invalid_argument("a body needs exactly one odometry source with predict (has " +
                                std::to_string(predicting) + ")");
}

Eigen::Matrix3d MultiSourceEkf::increment_noise(const PlanarOdometry& prev, const PlanarOdometry& cur,
                                                double min_variance) {
  if (cur.increment_covariance) return floor_eigenvalues(*cur.increment_covariance, min_variance);
  const Eigen::Matrix3d A = prev.pose.between(cur.pose).inverse().adjoint();
  return floor_eigenvalues(cur.covariance - A * prev.covariance * A.transpose(), min_variance);
}

void MultiSourceEkf::advance(int64_t utime) {
  clock_ = std::max(clock_, utime);
  for (auto& [name, s] : sources_) {
    auto& c = counters_[name];
    if (s.options.timeout_s <= 0 || c.silent || !s.last) continue;
    if (static_cast<double>(clock_ - s.last_seen) > s.options.timeout_s * 1e6) {
      c.silent = true;
      ++c.timeouts;
      if (!s.options.predict) s.last.reset();  // re-anchor on its next message
    }
  }
}

OdometryOutcome MultiSourceEkf::odometry(const std::string& name, const PlanarOdometry& m) {
  return odometry(name, m, {}, {});
}

OdometryOutcome MultiSourceEkf::odometry(const std::string& name, const PlanarOdometry& m,
                                         const std::vector<int64_t>& stops,
                                         const std::function<void(size_t)>& at_stop) {
  auto it = sources_.find(name);
  if (it == sources_.end()) return OdometryOutcome::unknown_source;
  Source& s = it->second;
  SourceCounters& c = counters_[name];
  ++c.messages;
  if (s.last && m.utime <= s.last->utime) return OdometryOutcome::duplicate;
  advance(m.utime);
  s.last_seen = m.utime;
  c.silent = false;
  if (s.options.predict) {
    if (!started_) {
      ekf_.initialize(m.pose, initial_covariance_);
      started_ = true;
      s.last = m;
      utime_ = m.utime;
      return OdometryOutcome::initialized;
    }
    predict_through_stops(
        s.last->pose.between(m.pose), increment_noise(*s.last, m, min_variance_), s.last->utime, m.utime, stops,
        [this](const SE2& piece, const Eigen::Matrix3d& Q) { ekf_.predict(piece, Q); },
        [&at_stop](size_t i) {
          if (at_stop) at_stop(i);
        });
    s.last = m;
    utime_ = m.utime;
    return OdometryOutcome::predicted;
  }
  if (!started_) return OdometryOutcome::before_start;
  return measure(s, c, m);
}

OdometryOutcome MultiSourceEkf::measure(Source& s, SourceCounters& c, const PlanarOdometry& m) {
  const auto& f = s.options.fuse;
  const bool relative = any(f, 3, 6) || s.options.differential;
  if (!s.last) {  // anchor: nothing to fuse yet
    if (relative) {
      if (s.clone < 0)
        s.clone = ekf_.add_pose_clone();
      else
        ekf_.refresh_clone(s.clone);
    }
    if (any(f, 0, 3) && !s.options.differential) s.frame = ekf_.pose() * m.pose.inverse();
    s.last = m;
    return OdometryOutcome::anchored;
  }
  // Every update this message makes must be accepted; the first refusal is the outcome.
  UpdateResult r;
  r.accepted = true;
  const auto combine = [&r](const UpdateResult& u) {
    if (r.accepted && !u.accepted) r = u;
  };
  if (any(f, 3, 6)) {  // velocities, integrated over the interval
    if (m.twist && s.last->twist) {
      const double dt = static_cast<double>(m.utime - s.last->utime) * 1e-6;
      const Eigen::Vector3d v = 0.5 * (*m.twist + *s.last->twist);
      const Eigen::Matrix3d R =
          floor_eigenvalues(0.5 * (m.twist_covariance + s.last->twist_covariance) * dt * dt, min_variance_);
      combine(ekf_.observe_relative_pose(s.clone, SE2::exp(v * dt), R, {f[3], f[4], f[5]}, s.options.gate));
    } else {
      UpdateResult u;
      u.reason = UpdateReason::kNoTwist;
      combine(u);
    }
  }
  if (any(f, 0, 3)) {
    const std::array<bool, 3> rows{f[0], f[1], f[2]};
    if (s.options.differential)
      combine(ekf_.observe_relative_pose(s.clone, s.last->pose.between(m.pose),
                                         increment_noise(*s.last, m, min_variance_), rows, s.options.gate));
    else
      combine(ekf_.observe_pose(s.frame, m.pose, floor_eigenvalues(m.covariance, min_variance_), rows, s.options.gate));
  }
  if (relative) ekf_.refresh_clone(s.clone);
  s.last = m;
  if (r.accepted) {
    ++c.fused;
    return OdometryOutcome::fused;
  }
  if (r.reason == UpdateReason::kGate) {
    ++c.gated;
    return OdometryOutcome::gated;
  }
  ++c.rejected;
  return OdometryOutcome::rejected;
}

namespace {
void save_odometry(archive::ArchiveWriter& w, const PlanarOdometry& m) {
  w(m.utime)(m.pose)(m.covariance)(m.increment_covariance)(m.twist)(m.twist_covariance);
}
void load_odometry(archive::ArchiveReader& r, PlanarOdometry& m) {
  r(m.utime)(m.pose)(m.covariance)(m.increment_covariance)(m.twist)(m.twist_covariance);
}
}  // namespace

void MultiSourceEkf::save(archive::ArchiveWriter& w) const {
  w(ekf_)(started_)(utime_)(clock_);
  w(static_cast<uint64_t>(sources_.size()));
  for (const auto& [name, s] : sources_) {
    w(name)(s.last.has_value());
    if (s.last) save_odometry(w, *s.last);
    w(s.last_seen)(s.clone)(s.frame);
  }
  w(static_cast<uint64_t>(counters_.size()));
  for (const auto& [name, c] : counters_) w(name)(c.messages)(c.fused)(c.gated)(c.rejected)(c.timeouts)(c.silent);
}

void MultiSourceEkf::load(archive::ArchiveReader& r) {
  r(ekf_)(started_)(utime_)(clock_);
  const uint64_t n = r.count(1, "the odometry sources");
  for (uint64_t i = 0; i < n; ++i) {
    const auto name = r.get<std::string>();
    auto it = sources_.find(name);
    if (it == sources_.end()) r.fail("odometry source '" + name + "' is not in this configuration");
    Source& s = it->second;
    if (r.get<bool>()) {
      PlanarOdometry m;
      load_odometry(r, m);
      s.last = m;
    } else {
      s.last.reset();
    }
    r(s.last_seen)(s.clone)(s.frame);
  }
  const uint64_t c = r.count(1, "the source counters");
  counters_.clear();
  for (uint64_t i = 0; i < c; ++i) {
    SourceCounters& k = counters_[r.get<std::string>()];
    r(k.messages)(k.fused)(k.gated)(k.rejected)(k.timeouts)(k.silent);
  }
}

}  // namespace sextant::filter
