#include "assoc/field_of_view.hpp"

#include "assoc/bearing_model.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace sextant::assoc {
namespace {

double wrap(double a) {
  a = std::remainder(a, 2 * M_PI);
  return a <= -M_PI ? a + 2 * M_PI : a;
}

}  // namespace

FieldOfView field_of_view(const Eigen::Vector3d& sensor, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                          double pad) {
  if (!sensor.allFinite() || !lo.allFinite() || !hi.allFinite() || !std::isfinite(pad))
    throw std::invalid_argument("field_of_view: non-finite sensor, region or padding");
  if (!(lo.array() <= hi.array()).all())
    throw std::invalid_argument("field_of_view: empty region (lower bound above upper)");
  FieldOfView f;
  const auto centre = bearing(sensor, 0.5 * (lo + hi));
  f.centre_azimuth = centre ? (*centre)[0] : 0.0;
  f.azimuth_lo = f.elevation_lo = 1e9, f.azimuth_hi = f.elevation_hi = -1e9;
  constexpr int kSteps = 16;
  for (int i = 0; i <= kSteps; ++i)
    for (int j = 0; j <= kSteps; ++j)
      for (double z : {lo.z(), hi.z()}) {
        const Eigen::Vector3d x(lo.x() + (hi.x() - lo.x()) * i / kSteps, lo.y() + (hi.y() - lo.y()) * j / kSteps, z);
        const auto h = bearing(sensor, x);
        if (!h) continue;
        const double az = wrap((*h)[0] - f.centre_azimuth);
        f.azimuth_lo = std::min(f.azimuth_lo, az), f.azimuth_hi = std::max(f.azimuth_hi, az);
        f.elevation_lo = std::min(f.elevation_lo, (*h)[1]), f.elevation_hi = std::max(f.elevation_hi, (*h)[1]);
      }
  const bool inside = sensor.x() >= lo.x() && sensor.x() <= hi.x() && sensor.y() >= lo.y() && sensor.y() <= hi.y();
  if (inside || f.azimuth_lo > f.azimuth_hi) f.azimuth_lo = -M_PI, f.azimuth_hi = M_PI;  // all around
  if (f.elevation_lo > f.elevation_hi) f.elevation_lo = -M_PI / 2, f.elevation_hi = M_PI / 2;
  f.azimuth_lo -= pad, f.azimuth_hi += pad, f.elevation_lo -= pad, f.elevation_hi += pad;
  if (f.azimuth_hi - f.azimuth_lo > 2 * M_PI) f.azimuth_lo = -M_PI, f.azimuth_hi = M_PI;
  f.elevation_lo = std::max(f.elevation_lo, -M_PI / 2), f.elevation_hi = std::min(f.elevation_hi, M_PI / 2);
  return f;
}

}  // namespace sextant::assoc
