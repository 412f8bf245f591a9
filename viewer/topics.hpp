#pragma once
// What sextant's LCM channels look like in Foxglove: the one mapping from LCM messages to viewer topics and schemas,
// shared by the live bridge (`sextant foxglove`) and the MCAP files (`sextant convert mcap`, `replay --mcap-out`), so
// both show the same scene.  Every message is JSON with a JSON Schema.
//
//   LCM message (any channel)   topic                               schema
//   every sextant type          the LCM channel, as-is              sextant.<type> (generated from its .lcm file)
//   fused_pose_t                /sextant/<source>/<estimator>/pose  foxglove.PoseInFrame in the pose's map frame (below)
//                               /tf                                 foxglove.FrameTransforms: <map frame> -> <source>/
//                                                                   <estimator>, and <map frame> -> <source> from its
//                                                                   best estimator so far (graph, then ekf, pf,
//                                                                   dead_reckoning); one message per pose, or per batch
//                                                                   (batch_frame_transforms)
//   geo_pose_t                  /sextant/<source>/<estimator>/fix   foxglove.LocationFix (the Map panel): latitude,
//                                                                   longitude, altitude and the ENU covariance
//   trajectory_t                /sextant/trajectories               foxglove.SceneUpdate: each body's optimized trajectory
//                                                                   rebuilt as trajectory_t.lcm says, a line strip + label
//   landmark_map_t              /sextant/landmark_map               foxglove.SceneUpdate: each map frame's landmarks,
//                                                                   a sphere + its id per landmark, drawn once all the
//                                                                   chunks of a publication are there, replacing the
//                                                                   frame's previous map (none once the frame joined
//                                                                   another)
//   (the above)                 /sextant/frames                     foxglove.SceneUpdate: a text at map's origin listing
//                                                                   the map frames, their bodies, which are unplaced
//   targets_t                   /sextant/targets                    foxglove.SceneUpdate: 95 % covariance ellipsoids + labels
//   bearing_scan_t              /sextant/bearings                   foxglove.SceneUpdate: the sensor (cube) and a ray per detection
//   landmarks_t                 /sextant/landmarks                  foxglove.SceneUpdate: each sighting placed from the body's
//                                                                   current pose, in its frame (rays and points)
//   truth_t                     /sextant/truth (landmark, target)   foxglove.SceneUpdate: spheres
//                               /sextant/<source>/truth/pose        foxglove.PoseInFrame (robot)
//   SEXTANT_STATUS (status_t) is its as-is topic: counters and latencies plot as /SEXTANT_STATUS.stages[:]{name=="graph"}...
// Map frames (fleets): each estimate is drawn in the map frame its message names (fused_pose_t.frame,
// trajectory_t.frame, landmark_map_t.frame): the frame named by a body, as the viewer frame "<name>/map" ("<name>"
// is the body's own frame); an empty name (logs from before fleets) is "map" itself.  "map" is the root and the
// display frame, and every map frame hangs from it by an identity transform, sent in each /tf message that has
// transforms from that frame or comes with a scene drawn in it, so that every frame has a path to the display frame
// whenever a viewer connects.  The map frame first by name is the fleet's (a join moves the frame of the later name
// into the earlier one, never the other way): "map" is that frame.  The others are frames not placed in it (a body not
// joined yet, or the filters, which stay in their body's own frame): the outputs carry no transform between them, so
// they are drawn at map's origin, and /sextant/frames says they are unplaced.  truth_t stays in "map": it is in
// the simulator's world frame, which is the robot's frame in a one-robot simulation (its odometry starts at its true
// pose) but not in a fleet's (each odometry starts at its own origin).
// A message whose bytes are not a sextant type (unknown fingerprint, malformed) has no JSON form: MCAP files keep it
// as raw LCM bytes on the topic "lcm_raw/<channel>" (message encoding "lcm", no schema) so that converting back
// loses nothing; the bridge counts and drops it.
#include "viewer/lcm_json.hpp"

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace sextant::viewer {

struct TopicSchema {
  std::string name;      // "foxglove.PoseInFrame", "sextant.fused_pose_t"
  std::string encoding;  // "jsonschema"
  std::string data;      // the schema text
};

/// One message for a viewer.
struct ViewerMessage {
  std::string topic;
  const TopicSchema* schema = nullptr;  // nullptr for raw LCM bytes
  std::string encoding;                 // "json", or "lcm" for raw bytes
  std::string lcm_channel;              // the LCM channel when this is a channel's as-is (or raw) form, else ""
  std::string data;                     // the payload
};

/// The schema of each sextant type and each Foxglove schema used, by name; nullptr when unknown.
const TopicSchema* topic_schema(const std::string& name);

struct TopicMapperOptions {
  /// Keep messages without a JSON form as raw LCM bytes (MCAP files) instead of dropping them (the bridge).
  bool keep_raw = false;
  /// Check that the JSON form converts back to the same bytes; a message that does not (a string that is not
  /// UTF-8) is kept raw.  MCAP files turn it on so that `convert lcm` is exact.
  bool check_round_trip = false;
  double bearing_ray_length_m = 60;  // how far a bearing ray is drawn from its sensor
  /// Gather the frame transforms of successive fused poses, all of them in order, into one /tf message that
  /// flush() appends, instead of one message per pose: the bridge flushes after each batch of messages it maps
  /// together, so that a viewer receives fewer, larger /tf messages and nothing later.
  bool batch_frame_transforms = false;
};

struct TopicMapperCounts {
  int64_t messages = 0;     // LCM messages mapped
  int64_t raw = 0;          // without a JSON form: kept raw (keep_raw) or dropped
  int64_t view_errors = 0;  // a Foxglove view that could not be built (the as-is topic still went out)
};

/// Turns LCM messages into viewer messages, in the order they arrive.  Stateful: trajectories are rebuilt, each
/// body's latest pose places its landmark sightings.  One per output (a bridge, a file); not thread-safe.
class TopicMapper {
 public:
  explicit TopicMapper(TopicMapperOptions options = {});
  ~TopicMapper();
  TopicMapper(TopicMapper&&) noexcept;
  TopicMapper& operator=(TopicMapper&&) noexcept;

  /// Appends to `out` what the LCM message `data` on `channel` becomes.
  void map(const std::string& channel, const uint8_t* data, size_t size, std::vector<ViewerMessage>& out);
  /// Appends the /tf message of the transforms gathered since the last call (batch_frame_transforms), if any.
  void flush(std::vector<ViewerMessage>& out);
  const TopicMapperCounts& counts() const { return counts_; }

 private:
  struct Views;
  TopicMapperOptions options_;
  std::unique_ptr<Views> views_;
  TopicMapperCounts counts_;
};

}  // namespace sextant::viewer
