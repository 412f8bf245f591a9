#include "eval/interpolated_trajectory.hpp"

#include <algorithm>

namespace sextant::tools {

InterpolatedTrajectory::InterpolatedTrajectory(std::vector<std::pair<int64_t, SE3>> samples) {
  std::stable_sort(samples.begin(), samples.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  samples_.reserve(samples.size());
  for (auto& s : samples) {
    if (!s.second.translation().allFinite() || !s.second.rotation().quaternion().coeffs().allFinite()) {
      ++dropped_;
      continue;
    }
    if (!samples_.empty() && samples_.back().first == s.first) continue;  // the first of equal stamps stays
    samples_.push_back(std::move(s));
  }
}

std::optional<SE3> InterpolatedTrajectory::at(int64_t utime) const {
  if (samples_.empty() || utime < samples_.front().first || utime > samples_.back().first) return std::nullopt;
  // The first sample at or after utime.
  const auto hi =
      std::lower_bound(samples_.begin(), samples_.end(), utime, [](const auto& s, int64_t t) { return s.first < t; });
  if (hi->first == utime) return hi->second;
  const auto lo = hi - 1;
  const double s = static_cast<double>(utime - lo->first) / static_cast<double>(hi->first - lo->first);
  const Eigen::Vector3d p = (1 - s) * lo->second.translation() + s * hi->second.translation();
  const Eigen::Quaterniond q = lo->second.rotation().quaternion().slerp(s, hi->second.rotation().quaternion());
  return SE3(q, p);
}

}  // namespace sextant::tools
