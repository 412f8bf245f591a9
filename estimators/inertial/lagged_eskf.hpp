#pragma once
// The error-state filter (error_state_ekf.hpp) with late measurements applied where they belong in time, as
// robot_localization's `smooth_lagged_data` / `history_length` does: GNSS fixes typically arrive 0.1-0.3 s after
// their stamp, while the IMU runs ahead.
//
// How: every input (an IMU sample or a measurement) is kept in a time-ordered history with the filter as it was
// right after it.  A measurement stamped before the newest input is inserted at its time: the filter is restored
// from the last input at or before that time, propagated to the stamp, updated, and every later input is applied
// again in order.  The result equals that of a filter that received every input in time order (the tests check
// this to 1e-9).  The history covers `history_s` seconds before the newest input (bounded memory: about 2 KB per
// input, so 1 s of a 1 kHz IMU is 2 MB); a measurement older than that is refused (UpdateReason::kTooOld), as is
// an IMU sample older than the newest IMU sample (samples are expected in order).
#include "estimators/inertial/error_state_ekf.hpp"

#include <deque>
#include <functional>

namespace sextant::inertial {

class LaggedEskf {
 public:
  /// A measurement update, applied to the filter brought to the measurement's time.
  using Update = std::function<filter::UpdateResult(ErrorStateEkf&)>;

  LaggedEskf(const EskfOptions& options, double history_s);

  void initialize(double t, const EskfState& x, const ErrorStateEkf::Matrix15& P);
  /// An IMU sample, in order among the samples (out_of_order when older than the newest sample); one older than a
  /// measurement already applied goes before it, and the measurement is applied again after it.
  ImuResult add_imu(double t, const BodyImuSample& sample);
  /// A measurement stamped t: applied now when t is at or after the newest input, else inserted in the history and
  /// the later inputs re-applied; refused (kTooOld) when t is before the history, or before the first IMU sample.
  filter::UpdateResult add_measurement(double t, const Update& update);

  /// The filter after every input so far.
  const ErrorStateEkf& filter() const { return current_; }
  /// Inputs re-applied because of late measurements, since the start (a cost counter).
  int64_t replayed() const { return replayed_; }
  size_t history_size() const { return history_.size(); }

 private:
  struct Entry {
    double t = 0;
    bool imu = false;
    BodyImuSample sample;
    Update update;
    ErrorStateEkf after;  // the filter right after this input
  };
  filter::UpdateResult apply(Entry& e, ErrorStateEkf& f) const;
  /// Inserts an input older than the newest one and re-applies every later input.
  filter::UpdateResult add_late(Entry e);
  void trim();

  double history_s_;
  ErrorStateEkf current_;
  std::deque<Entry> history_;
  int64_t replayed_ = 0;
};

}  // namespace sextant::inertial
