#include "estimators/keyframe/keyframe_thinning.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>

namespace sextant {

KeyframePlace place_of(const SE3& x, bool planar, const KeyframeThinningOptions& o) {
  const Eigen::Vector3d& t = x.translation();
  const Eigen::Vector3d ahead = x.rotation().matrix().col(0);
  const double heading = std::atan2(ahead.y(), ahead.x()) + M_PI;  // [0, 2 pi]
  const auto sectors = std::max<int64_t>(1, static_cast<int64_t>(std::llround(2 * M_PI / o.heading_sector)));
  auto cell = [&](double v) { return static_cast<int64_t>(std::floor(v / o.cell_size)); };
  return {cell(t.x()), cell(t.y()), planar ? 0 : cell(t.z()),
          static_cast<int64_t>(std::floor(heading / (2 * M_PI) * static_cast<double>(sectors))) % sectors};
}

std::vector<char> keyframes_to_keep(const std::vector<ThinningCandidate>& keyframes, bool planar,
                                    const KeyframeThinningOptions& o) {
  if (o.window < 1) throw std::invalid_argument("keyframe thinning: window must be at least 1");
  if (!(o.cell_size > 0) || !std::isfinite(o.cell_size))
    throw std::invalid_argument("keyframe thinning: cell_size must be > 0");
  if (!(o.heading_sector > 0) || !std::isfinite(o.heading_sector))
    throw std::invalid_argument("keyframe thinning: heading_sector must be > 0");
  const size_t n = keyframes.size();
  std::vector<char> keep(n, 0);
  const size_t window_start = n > static_cast<size_t>(o.window) ? n - static_cast<size_t>(o.window) : 0;
  std::set<KeyframePlace> taken;
  for (size_t i = 0; i < n; ++i) {
    const KeyframePlace p = place_of(keyframes[i].pose, planar, o);
    if (i == 0 || i >= window_start) {
      keep[i] = 1;
      if (i < window_start) taken.insert(p);
      continue;
    }
    keep[i] = taken.insert(p).second ? 1 : 0;  // the earliest keyframe of its place
  }
  return keep;
}

}  // namespace sextant
