#pragma once
// A prediction over an odometry interval [t0, t1] that stops at stamps inside it, so that measurements taken
// between two odometry messages update the pose they were taken from: the increment Delta is split by
// interpolation on the group, Delta_a = Exp(a Log Delta) with a = (t - t0) / (t1 - t0), and its noise Q in
// proportion, (a_i - a_{i-1}) Q per piece (noise accumulated along the path).  Works for SE2 and SE3.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace sextant::filter {

/// Calls predict(piece, noise) for each piece and at_stop(i) once the prediction has reached stops[i].  Stops
/// outside (t0, t1) are skipped; repeated stops call at_stop without predicting; `stops` should be increasing.
template <class Group, class Covariance, class Predict, class AtStop>
void predict_through_stops(const Group& delta, const Covariance& Q, int64_t t0, int64_t t1,
                           const std::vector<int64_t>& stops, Predict&& predict, AtStop&& at_stop) {
  const auto tau = delta.log();
  const auto span = static_cast<double>(t1 - t0);
  Group reached;  // identity: the part of delta predicted so far
  double done = 0;
  for (size_t i = 0; i < stops.size(); ++i) {
    if (stops[i] <= t0 || stops[i] >= t1) continue;
    const double a = static_cast<double>(stops[i] - t0) / span;
    if (a > done) {
      const Group target = Group::exp(a * tau);
      predict(reached.between(target), Covariance((a - done) * Q));
      reached = target, done = a;
    }
    at_stop(i);
  }
  predict(reached.between(delta), Covariance((1 - done) * Q));
}

}  // namespace sextant::filter
