#pragma once
// The engine's events and the values stages keep of them in the binary archive (estimators/archive/
// binary_archive.hpp): what a stage's saved state holds of its inputs (waiting loops and sightings, a filter's
// window of recent inputs) and of its outputs (the graph's map -> odometry correction).  Every field is written,
// exactly.
#include "daemon/engine/events.hpp"
#include "daemon/engine/graph_correction.hpp"
#include "estimators/archive/binary_archive.hpp"
#include "estimators/lie/lie_archive.hpp"

namespace sextant::engine {

inline void save(archive::ArchiveWriter& w, const Pose& p) { w(p.position)(p.orientation); }
inline void load(archive::ArchiveReader& r, Pose& p) { r(p.position)(p.orientation); }

inline void save(archive::ArchiveWriter& w, const Odometry::Twist& t) { w(t.linear)(t.angular)(t.covariance); }
inline void load(archive::ArchiveReader& r, Odometry::Twist& t) { r(t.linear)(t.angular)(t.covariance); }

inline void save(archive::ArchiveWriter& w, const Odometry& o) {
  w(o.utime)(o.source)(o.planar)(o.pose)(o.covariance)(o.increment_covariance)(o.twist);
}
inline void load(archive::ArchiveReader& r, Odometry& o) {
  r(o.utime)(o.source)(o.planar)(o.pose)(o.covariance)(o.increment_covariance)(o.twist);
}

inline void save(archive::ArchiveWriter& w, const LandmarkObservation& o) {
  w(o.id)(o.range)(o.azimuth)(o.elevation)(o.covariance);
}
inline void load(archive::ArchiveReader& r, LandmarkObservation& o) {
  r(o.id)(o.range)(o.azimuth)(o.elevation)(o.covariance);
}

inline void save(archive::ArchiveWriter& w, const LandmarkSightings& s) {
  w(s.utime)(s.source)(s.planar)(s.sensor_in_body)(s.observations);
}
inline void load(archive::ArchiveReader& r, LandmarkSightings& s) {
  r(s.utime)(s.source)(s.planar)(s.sensor_in_body)(s.observations);
}

inline void save(archive::ArchiveWriter& w, const LoopClosure& l) {
  w(l.utime)(l.source)(l.planar)(l.utime_from)(l.utime_to)(l.keyframe_from)(l.keyframe_to)(l.request_id)(l.relative)(
      l.information)(l.matcher)(l.score);
}
inline void load(archive::ArchiveReader& r, LoopClosure& l) {
  r(l.utime)(l.source)(l.planar)(l.utime_from)(l.utime_to)(l.keyframe_from)(l.keyframe_to)(l.request_id)(l.relative)(
      l.information)(l.matcher)(l.score);
}

inline void save(archive::ArchiveWriter& w, const BearingDetection& d) {
  w(d.azimuth)(d.elevation)(d.sigma_azimuth)(d.sigma_elevation);
}
inline void load(archive::ArchiveReader& r, BearingDetection& d) {
  r(d.azimuth)(d.elevation)(d.sigma_azimuth)(d.sigma_elevation);
}

inline void save(archive::ArchiveWriter& w, const BearingScan& s) {
  w(s.utime)(s.sensor_id)(s.sensor_position)(s.scan_id)(s.detections);
}
inline void load(archive::ArchiveReader& r, BearingScan& s) {
  r(s.utime)(s.sensor_id)(s.sensor_position)(s.scan_id)(s.detections);
}

inline void save(archive::ArchiveWriter& w, const GraphCorrection& c) {
  w(c.keyframe_utime)(c.keyframe_odom)(c.keyframe_map)(c.keyframe_covariance)(c.keyframe_odom_covariance);
}
inline void load(archive::ArchiveReader& r, GraphCorrection& c) {
  r(c.keyframe_utime)(c.keyframe_odom)(c.keyframe_map)(c.keyframe_covariance)(c.keyframe_odom_covariance);
}

}  // namespace sextant::engine
