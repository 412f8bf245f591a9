#pragma once
// A passive sensor's field of view over a surveillance region (the clutter model of sim/assoc_experiment.hpp):
// the azimuth-elevation bounding box of an axis-aligned box region seen from the sensor, padded on every side.  Its area psi (rad^2) turns an
// expected number of false alarms per scan into the false-alarm density of the association cost,
// lambda = false alarms / psi, and false alarms can be drawn uniformly in it.
#include <Eigen/Core>

namespace sextant::assoc {

struct FieldOfView {
  double centre_azimuth = 0;              // azimuth of the region's centre, rad; the azimuth bounds are relative to it
  double azimuth_lo = 0, azimuth_hi = 0;  // rad, relative to centre_azimuth, width at most 2 pi
  double elevation_lo = 0, elevation_hi = 0;  // rad, within [-pi/2, pi/2]
  double area() const { return (azimuth_hi - azimuth_lo) * (elevation_hi - elevation_lo); }  // rad^2
};

/// The field of view of a sensor at `sensor` over the box [region_lo, region_hi] (same frame and unit), padded by
/// `pad` rad.  The box's faces are sampled (17 x 17 points on each horizontal face: the elevation extremes need
/// not be at corners).  A sensor inside the region's horizontal extent sees all azimuths (width 2 pi).  Throws
/// std::invalid_argument when the region is empty (lo > hi on an axis) or a bound is not finite.
FieldOfView field_of_view(const Eigen::Vector3d& sensor, const Eigen::Vector3d& region_lo,
                          const Eigen::Vector3d& region_hi, double pad);

}  // namespace sextant::assoc
