#pragma once
// The engine's events and the values stages keep of them in the binary archive (estimators/archive/
// binary_archive.hpp): what a stage's saved state holds of its inputs (waiting loops and sightings, a filter's
// window of recent inputs) and of its outputs (the graph's map -> odometry correction).  Every field is written,
// exactly.
#include "daemon/engine/events.hpp"
#include "daemon/engine/graph_correction.hpp"
#include "estimators/archive/binary_archive.hpp"
#include "estimators/lie/lie_archive.hpp"

#include <type_traits>

namespace sextant::engine {

/// One field list per type serves both directions: save(w, x) and load(r, x) call fields(a, x) with the writer or
/// the reader, so the order written is the order read.

template <class Archive, class X>
std::enable_if_t<std::is_same_v<std::remove_const_t<X>, Pose>> fields(Archive& a, X& p) {
  a(p.position)(p.orientation);
}
inline void save(archive::ArchiveWriter& w, const Pose& p) { fields(w, p); }
inline void load(archive::ArchiveReader& r, Pose& p) { fields(r, p); }

template <class Archive, class X>
std::enable_if_t<std::is_same_v<std::remove_const_t<X>, Odometry::Twist>> fields(Archive& a, X& t) {
  a(t.linear)(t.angular)(t.covariance);
}
inline void save(archive::ArchiveWriter& w, const Odometry::Twist& t) { fields(w, t); }
inline void load(archive::ArchiveReader& r, Odometry::Twist& t) { fields(r, t); }

template <class Archive, class X>
std::enable_if_t<std::is_same_v<std::remove_const_t<X>, Odometry>> fields(Archive& a, X& o) {
  a(o.utime)(o.source)(o.planar)(o.pose)(o.covariance)(o.increment_covariance)(o.twist);
}
inline void save(archive::ArchiveWriter& w, const Odometry& o) { fields(w, o); }
inline void load(archive::ArchiveReader& r, Odometry& o) { fields(r, o); }

template <class Archive, class X>
std::enable_if_t<std::is_same_v<std::remove_const_t<X>, LandmarkObservation>> fields(Archive& a, X& o) {
  a(o.id)(o.range)(o.azimuth)(o.elevation)(o.covariance);
}
inline void save(archive::ArchiveWriter& w, const LandmarkObservation& o) { fields(w, o); }
inline void load(archive::ArchiveReader& r, LandmarkObservation& o) { fields(r, o); }

template <class Archive, class X>
std::enable_if_t<std::is_same_v<std::remove_const_t<X>, LandmarkSightings>> fields(Archive& a, X& s) {
  a(s.utime)(s.source)(s.planar)(s.sensor_in_body)(s.observations);
}
inline void save(archive::ArchiveWriter& w, const LandmarkSightings& s) { fields(w, s); }
inline void load(archive::ArchiveReader& r, LandmarkSightings& s) { fields(r, s); }

template <class Archive, class X>
std::enable_if_t<std::is_same_v<std::remove_const_t<X>, LoopClosure>> fields(Archive& a, X& l) {
  a(l.utime)(l.source)(l.planar)(l.utime_from)(l.utime_to)(l.keyframe_from)(l.keyframe_to)(l.request_id)(l.relative)(
      l.information)(l.matcher)(l.score);
}
inline void save(archive::ArchiveWriter& w, const LoopClosure& l) { fields(w, l); }
inline void load(archive::ArchiveReader& r, LoopClosure& l) { fields(r, l); }

template <class Archive, class X>
std::enable_if_t<std::is_same_v<std::remove_const_t<X>, BearingDetection>> fields(Archive& a, X& d) {
  a(d.azimuth)(d.elevation)(d.sigma_azimuth)(d.sigma_elevation);
}
inline void save(archive::ArchiveWriter& w, const BearingDetection& d) { fields(w, d); }
inline void load(archive::ArchiveReader& r, BearingDetection& d) { fields(r, d); }

template <class Archive, class X>
std::enable_if_t<std::is_same_v<std::remove_const_t<X>, BearingScan>> fields(Archive& a, X& s) {
  a(s.utime)(s.sensor_id)(s.sensor_position)(s.scan_id)(s.detections);
}
inline void save(archive::ArchiveWriter& w, const BearingScan& s) { fields(w, s); }
inline void load(archive::ArchiveReader& r, BearingScan& s) { fields(r, s); }

template <class Archive, class X>
std::enable_if_t<std::is_same_v<std::remove_const_t<X>, GraphCorrection>> fields(Archive& a, X& c) {
  a(c.keyframe_utime)(c.keyframe_odom)(c.keyframe_map)(c.keyframe_covariance)(c.keyframe_odom_covariance)(c.frame);
}
inline void save(archive::ArchiveWriter& w, const GraphCorrection& c) { fields(w, c); }
inline void load(archive::ArchiveReader& r, GraphCorrection& c) { fields(r, c); }

}  // namespace sextant::engine
