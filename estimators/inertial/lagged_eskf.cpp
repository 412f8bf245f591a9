#include "estimators/inertial/lagged_eskf.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>

namespace sextant::inertial {
namespace {

filter::UpdateResult too_old() {
  filter::UpdateResult r;
  r.reason = filter::UpdateReason::kTooOld;
  return r;
}

}  // namespace

LaggedEskf::LaggedEskf(const EskfOptions& options, double history_s) : history_s_(history_s), current_(options) {}

void LaggedEskf::initialize(double t, const EskfState& x, const ErrorStateEkf::Matrix15& P) {
  current_.initialize(t, x, P);
  history_.clear();
}

filter::UpdateResult LaggedEskf::apply(Entry& e, ErrorStateEkf& f) const {
  filter::UpdateResult r;
  if (e.imu) {
    const ImuResult i = f.add_imu(e.t, e.sample);
    r.accepted = i == ImuResult::propagated || i == ImuResult::started || i == ImuResult::gap;
  } else {
    r = f.propagate_to(e.t) ? e.update(f) : too_old();
  }
  e.after = f;
  return r;
}

void LaggedEskf::trim() {
  // Keep one input at or before the window's start: the base a measurement at the start is applied on.
  const double start = history_.back().t - history_s_;
  while (history_.size() > 1 && history_[1].t <= start) history_.pop_front();
}

ImuResult LaggedEskf::add_imu(double t, const BodyImuSample& sample) {
  const auto newest_imu = std::find_if(history_.rbegin(), history_.rend(), [](const Entry& e) { return e.imu; });
  if (newest_imu != history_.rend() && t < newest_imu->t) return ImuResult::out_of_order;
  if (!current_.initialized()) return ImuResult::not_initialized;
  if (!std::isfinite(t) || !sample.gyro.allFinite() || !sample.accel.allFinite()) return ImuResult::non_finite;
  Entry e;
  e.t = t;
  e.imu = true;
  e.sample = sample;
  if (history_.empty() || t >= history_.back().t) {
    const ImuResult r = current_.add_imu(t, sample);
    e.after = current_;
    history_.push_back(std::move(e));
    trim();
    return r;
  }
  // After measurements stamped later than this sample: it goes before them and they are applied again.
  return add_late(std::move(e)).accepted ? ImuResult::propagated : ImuResult::out_of_order;
}

filter::UpdateResult LaggedEskf::add_measurement(double t, const Update& update) {
  if (!std::isfinite(t)) {
    filter::UpdateResult r;
    r.reason = filter::UpdateReason::kNonFinite;
    return r;
  }
  Entry e;
  e.t = t;
  e.update = update;
  if (history_.empty() || t >= history_.back().t) {
    const filter::UpdateResult r = apply(e, current_);
    history_.push_back(std::move(e));
    trim();
    return r;
  }
  return add_late(std::move(e));
}

filter::UpdateResult LaggedEskf::add_late(Entry e) {
  // The first input stamped after e (inputs at the same time keep their arrival order).
  const auto pos =
      std::upper_bound(history_.begin(), history_.end(), e.t, [](double t, const Entry& x) { return t < x.t; });
  if (pos == history_.begin()) return too_old();
  ErrorStateEkf f = std::prev(pos)->after;
  const filter::UpdateResult r = apply(e, f);
  auto it = history_.insert(pos, std::move(e));
  for (++it; it != history_.end(); ++it, ++replayed_) apply(*it, f);
  current_ = f;
  trim();
  return r;
}

}  // namespace sextant::inertial
