#pragma once
// What the SLAM layer (slam_graph.hpp) takes: one body's odometry, loop closures and landmark sightings, as plain
// values.  Times are utime (int64 microseconds); poses are SE3 (SE(2) bodies: z, roll and pitch zero); tangent vectors
// and covariances are ordered translation first, then rotation, with the perturbation on the right
// (T = T_hat Exp(xi)); a planar body's matrices are 6x6 with its axes at x, y and yaw (estimators/lie/planar_axes.hpp).
#include "estimators/archive/binary_archive.hpp"
#include "estimators/lie/lie_archive.hpp"
#include "estimators/lie/se3.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace sextant::slam {

/// One odometry message of a body: its pose in the body's odometry frame and that pose's covariance; the covariance of
/// the motion since the previous message when the sender states it (else it is the growth of the pose covariance,
/// estimators/lie/pose_covariance.hpp).
struct OdometryInput {
  int64_t utime = 0;
  bool planar = false;
  SE3 pose;
  Matrix6d covariance = Matrix6d::Zero();
  std::optional<Matrix6d> increment_covariance;  // in the previous pose's frame
};

/// A relative pose between two times of a body, T_from^-1 T_to, with its information over the tangent; the keyframe
/// ids when the loop answers a proposal (-1: unknown, the ends are found by time, keyframe_track.hpp).
struct LoopInput {
  int64_t utime_from = 0, utime_to = 0;
  int64_t keyframe_from = -1, keyframe_to = -1;
  SE3 relative;
  Matrix6d information = Matrix6d::Identity();
  std::string body_to;  // the body of the "to" end when it is another body of the fleet (empty: the same body)

  template <class Archive, class Self>
  static void fields(Archive& a, Self& l) {
    a(l.utime_from)(l.utime_to)(l.keyframe_from)(l.keyframe_to)(l.relative)(l.information)(l.body_to);
  }
  void save(archive::ArchiveWriter& w) const { fields(w, *this); }
  void load(archive::ArchiveReader& r) { fields(r, *this); }
};

/// One landmark seen from the sensor: range (m), azimuth and elevation (rad, sensor frame; elevation unused on a planar
/// body) and their covariance; id -1 for a landmark the sender did not identify (left to the filters' association).
struct LandmarkSighting {
  int64_t id = -1;
  double range = 0, azimuth = 0, elevation = 0;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();  // over [range, azimuth, elevation]

  template <class Archive, class Self>
  static void fields(Archive& a, Self& s) {
    a(s.id)(s.range)(s.azimuth)(s.elevation)(s.covariance);
  }
  void save(archive::ArchiveWriter& w) const { fields(w, *this); }
  void load(archive::ArchiveReader& r) { fields(r, *this); }
};

/// The sightings of one body at one time, from a sensor mounted at `sensor_in_body`.
struct SightingsInput {
  int64_t utime = 0;
  bool planar = false;
  SE3 sensor_in_body;
  std::vector<LandmarkSighting> sightings;

  template <class Archive, class Self>
  static void fields(Archive& a, Self& s) {
    a(s.utime)(s.planar)(s.sensor_in_body)(s.sightings);
  }
  void save(archive::ArchiveWriter& w) const { fields(w, *this); }
  void load(archive::ArchiveReader& r) { fields(r, *this); }
};

}  // namespace sextant::slam
