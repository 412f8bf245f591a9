#pragma once
// What one body adds to the SLAM graph, as a value that another SlamGraph can apply to build the same graph: the
// unit a fleet of daemons exchanges (one daemon per robot, each feeding only its own robots' sensors).
//
// SlamGraph splits its work into a front end and a back end.  The front end needs the body's full odometry and runs
// only where the body's sensors arrive (its owner): keyframe selection, the odometry composed between keyframes,
// anchoring a sighting or a loop end at a time on a keyframe (keyframe_track.hpp).  Its results are contributions,
// each self-contained and expressed on keyframes by id.  The back end builds factors from contributions, gates them
// against the current estimate, places and joins frames and solves; it runs in every SlamGraph holding the body.  A
// graph fed a body's inputs applies the contributions it makes itself, so one daemon fed all the data and a daemon
// fed one robot's data plus the others' contributions build the graph from the same values.
//
// A sighting of another body (a marker, FleetOptions::markers) or a loop to another body needs both bodies' odometry
// at its time, which no single owner has when the bodies belong to different daemons.  Its observer's owner anchors
// its own end (a half: BodySightingHalf, BodyLoopHalf, in the observer's stream); the other body's owner anchors the
// other end and contributes the whole (BodySighting, BodyLoop, in that body's stream).  When both bodies are local the
// graph does both at once.
//
// Joining two map frames (frame_placement.hpp) is decided once, by the graph that owns the root body of the frame
// that moves (the later name): the others apply its decision (FrameJoin, in that root's stream) instead of running the
// placement rule on the evidence they happen to hold, which arrives in a different order on every daemon and could
// fold the maps differently.  Each frame moves at most once and only into a frame of an earlier name, so the
// decisions of several owners never conflict.
//
// Each body's contributions are applied in the order its owner made them (a stream; the exchange numbers them).  A
// whole sighting or loop between two bodies names keyframes of both: where the other body's keyframe has not arrived
// yet, it waits (bounded) and is applied when it does.
//
// Units and frames as slam_inputs.hpp: utime in microseconds, poses SE3 in the body's odometry frame, covariances and
// information 6x6 over the tangent, translation first, perturbation on the right.
#include "estimators/archive/binary_archive.hpp"
#include "estimators/lie/lie_archive.hpp"
#include "estimators/lie/se3.hpp"
#include "estimators/slam/slam_inputs.hpp"

#include <cstdint>
#include <string>
#include <variant>
#include <vector>

namespace sextant::slam {

/// A keyframe of the body: the odometry pose at its time and, after the first, the odometry edge from the previous
/// keyframe of the owner's graph with its covariance (composed message by message; a re-anchored jump's inflation
/// included).  The first keyframe of a body holds its frame's gauge.
struct KeyframeContribution {
  int64_t id = 0, utime = 0;
  bool planar = false;
  bool first = false;       // the body's first keyframe (no edge)
  bool reanchored = false;  // linked across an odometry jump (KeyframeSelector's kReanchored)
  SE3 odom;
  Matrix6d odom_covariance = Matrix6d::Zero();
  SE3 edge;
  Matrix6d edge_covariance = Matrix6d::Zero();
  template <class Archive, class Self>
  static void fields(Archive& a, Self& x) {
    a(x.id)(x.utime)(x.planar)(x.first)(x.reanchored)(x.odom)(x.odom_covariance)(x.edge)(x.edge_covariance);
  }
  void save(archive::ArchiveWriter& w) const { fields(w, *this); }
  void load(archive::ArchiveReader& r) { fields(r, *this); }
};

/// A time of the body anchored on one of its keyframes: the keyframe's id, the odometry motion D from it to the time
/// and D's covariance (TrackPoint by id instead of position: positions change when lifelong thinning runs).
struct KeyframeAnchor {
  int64_t keyframe = 0;
  SE3 motion;
  Matrix6d covariance = Matrix6d::Zero();
  template <class Archive, class Self>
  static void fields(Archive& a, Self& x) {
    a(x.keyframe)(x.motion)(x.covariance);
  }
  void save(archive::ArchiveWriter& w) const { fields(w, *this); }
  void load(archive::ArchiveReader& r) { fields(r, *this); }
};

/// Identified landmark sightings of one message (SightingsInput without the unidentified ones), anchored.  Sightings
/// of markers (other bodies) are not here: they are BodySightingHalf.
struct SightingsContribution {
  KeyframeAnchor anchor;
  SightingsInput sightings;
  template <class Archive, class Self>
  static void fields(Archive& a, Self& x) {
    a(x.anchor)(x.sightings);
  }
  void save(archive::ArchiveWriter& w) const { fields(w, *this); }
  void load(archive::ArchiveReader& r) { fields(r, *this); }
};

/// The observer's end of a sighting of another body: the observer's anchor, the sighting and the observed body.
struct BodySightingHalf {
  std::string observed;
  int64_t utime = 0;
  SE3 sensor_in_body;
  LandmarkSighting sighting;
  KeyframeAnchor observer;
  template <class Archive, class Self>
  static void fields(Archive& a, Self& x) {
    a(x.observed)(x.utime)(x.sensor_in_body)(x.sighting)(x.observer);
  }
  void save(archive::ArchiveWriter& w) const { fields(w, *this); }
  void load(archive::ArchiveReader& r) { fields(r, *this); }
};

/// A sighting of one body by another with both ends anchored, contributed by the observed body's owner.
struct BodySighting {
  std::string observer;
  int64_t utime = 0;
  SE3 sensor_in_body;
  LandmarkSighting sighting;
  KeyframeAnchor observer_anchor, observed_anchor;
  template <class Archive, class Self>
  static void fields(Archive& a, Self& x) {
    a(x.observer)(x.utime)(x.sensor_in_body)(x.sighting)(x.observer_anchor)(x.observed_anchor);
  }
  void save(archive::ArchiveWriter& w) const { fields(w, *this); }
  void load(archive::ArchiveReader& r) { fields(r, *this); }
};

/// A loop closure within the body, between two of its keyframes (loop_gate.hpp's KeyframeLoop by keyframe id).
struct LoopContribution {
  int64_t from_keyframe = 0, to_keyframe = 0;
  SE3 z;
  Matrix6d information = Matrix6d::Zero();
  bool widened = false;
  template <class Archive, class Self>
  static void fields(Archive& a, Self& x) {
    a(x.from_keyframe)(x.to_keyframe)(x.z)(x.information)(x.widened);
  }
  void save(archive::ArchiveWriter& w) const { fields(w, *this); }
  void load(archive::ArchiveReader& r) { fields(r, *this); }
};

/// The "from" end of a loop to another body (LoopInput::body_to), anchored by the from body's owner.
struct BodyLoopHalf {
  LoopInput loop;
  KeyframeAnchor from;
  template <class Archive, class Self>
  static void fields(Archive& a, Self& x) {
    a(x.loop)(x.from);
  }
  void save(archive::ArchiveWriter& w) const { fields(w, *this); }
  void load(archive::ArchiveReader& r) { fields(r, *this); }
};

/// A loop between keyframes of two bodies, contributed by the "to" body's owner.
struct BodyLoop {
  std::string from;
  int64_t from_keyframe = 0, to_keyframe = 0;
  SE3 z;
  Matrix6d information = Matrix6d::Zero();
  template <class Archive, class Self>
  static void fields(Archive& a, Self& x) {
    a(x.from)(x.from_keyframe)(x.to_keyframe)(x.z)(x.information);
  }
  void save(archive::ArchiveWriter& w) const { fields(w, *this); }
  void load(archive::ArchiveReader& r) { fields(r, *this); }
};

/// The frame whose root is the contributing body joins the frame whose root is `keep`: a point p of the moving frame
/// is keep_from_gone * p in keep's (both frames as they were when the owner decided; a graph where `keep`'s frame has
/// joined another since composes that join's placement).  The evidence between the two frames that agrees with the
/// placement becomes factors, the rest is counted as outliers (slam_graph_fleet.cpp).
struct FrameJoin {
  std::string keep;
  SE3 keep_from_gone;
  template <class Archive, class Self>
  static void fields(Archive& a, Self& x) {
    a(x.keep)(x.keep_from_gone);
  }
  void save(archive::ArchiveWriter& w) const { fields(w, *this); }
  void load(archive::ArchiveReader& r) { fields(r, *this); }
};

/// Lifelong thinning (slam_graph.hpp) is decided by a body's owner too: the keyframes of the body it took out of its
/// graph.  Another graph takes the same ones out at its own next thinning (until then it holds them: a graph larger
/// by a little for a while, the same keyframes after), so every daemon keeps the same keyframes of every body.
struct KeyframesThinned {
  std::vector<int64_t> keyframes;  // ids
  template <class Archive, class Self>
  static void fields(Archive& a, Self& x) {
    a(x.keyframes);
  }
  void save(archive::ArchiveWriter& w) const { fields(w, *this); }
  void load(archive::ArchiveReader& r) { fields(r, *this); }
};

/// One contribution of `body` (the stream it belongs to).
struct GraphContribution {
  using What = std::variant<KeyframeContribution, SightingsContribution, BodySightingHalf, BodySighting,
                            LoopContribution, BodyLoopHalf, BodyLoop, FrameJoin, KeyframesThinned>;
  std::string body;
  What what;

  /// In the binary archive: the body, the alternative's index, its fields (archive::ArchiveError when loading an
  /// index that names no alternative).
  void save(archive::ArchiveWriter& w) const { w(body)(what); }
  void load(archive::ArchiveReader& r) { r(body)(what); }
};

}  // namespace sextant::slam
