#pragma once
// The codec between LCM messages (lcmtypes/sextant/*.lcm) and the engine's typed events and outputs.
// Decoding validates: every number finite, quaternions of unit norm (within 1e-3; renormalised), covariances
// symmetric positive definite (information matrices too), array sizes consistent and bounded.  A message that
// fails is rejected with a reason and a message naming the field — never half-used.
#include "daemon/engine/outputs.hpp"

#include <sextant/bearing_scan_t.hpp>
#include <sextant/fleet_contribution_t.hpp>
#include <sextant/fleet_control_t.hpp>
#include <sextant/fused_pose_t.hpp>
#include <sextant/geo_pose_t.hpp>
#include <sextant/gnss_t.hpp>
#include <sextant/imu_t.hpp>
#include <sextant/landmarks_t.hpp>
#include <sextant/loop_closure_t.hpp>
#include <sextant/match_request_t.hpp>
#include <sextant/odometry_t.hpp>
#include <sextant/landmark_map_t.hpp>
#include <sextant/targets_t.hpp>
#include <sextant/trajectory_t.hpp>

#include <cstddef>
#include <string>
#include <variant>

namespace sextant::runtime {

/// Why an input message was dropped. `reason` is a short counter key for the status channel
/// ("decode", "fingerprint", "non_finite", "quaternion", "covariance", "too_large", "invalid"),
/// `message` names the field, e.g. "odometry_t.covariance: not positive definite (eigenvalue -0.2)".
struct Rejection {
  std::string reason;
  std::string message;
};

/// Largest arrays accepted in one message (a huge array is rejected, not allocated).
inline constexpr int kMaxObservationsPerMessage = 4096;
inline constexpr int kMaxDetectionsPerScan = 4096;

/// The kinds of input channel the daemon subscribes to (kFleet, kFleetControl: engine.graph.fleet.exchange).
enum class InputKind { kOdometry, kLandmarks, kBearings, kLoopClosures, kImu, kGnss, kFleet, kFleetControl };

using Decoded = std::variant<engine::Event, Rejection>;

/// Who sent a message: every sextant message carries the sender's name and a per-sender sequence number.
struct MessageOrigin {
  std::string sender;
  int64_t seq = 0;
};

/// Decodes raw bytes received on an input channel of the given kind, then validates (see `to_event`).  Never
/// throws: lengths and counts are checked against the bytes before lcm-gen's decode runs (wire_layout.hpp).
/// When the bytes decode, `origin` (if given) receives the sender and sequence number, even if validation fails.
Decoded decode_event(InputKind kind, const void* data, size_t size, MessageOrigin* origin = nullptr);

/// Validated conversions message -> event.
Decoded to_event(const sextant::odometry_t& msg);
Decoded to_event(const sextant::landmarks_t& msg);
Decoded to_event(const sextant::bearing_scan_t& msg);
Decoded to_event(const sextant::loop_closure_t& msg);
/// An IMU sample: each present group finite, its covariance symmetric positive semi-definite (zero: not stated), the
/// orientation a unit quaternion; at least one group present.
Decoded to_event(const sextant::imu_t& msg);
/// A GNSS fix: status a gnss_t.STATUS_* value, latitude in [-90, 90], longitude in [-180, 180], altitude within
/// 100 km of the ellipsoid, covariances symmetric positive semi-definite.  A message without a fix (STATUS_NO_FIX) is
/// refused with reason "no_fix": it carries nothing to fuse.
Decoded to_event(const sextant::gnss_t& msg);
/// A run of a fleet member's contribution stream (codec_fleet.cpp): sender and body names of 1 to 256 characters
/// without control characters, first in [1, 2^62], 1 to 1024 contributions, each with exactly the poses, anchors and
/// sightings its kind carries (fleet_item_t.lcm) and only its kind's flags; every number finite, quaternions of unit
/// norm, covariances and information matrices symmetric positive semi-definite, a sighting's range positive with its
/// range and azimuth variances, ids of keyframes and landmarks not negative.
Decoded to_event(const sextant::fleet_contribution_t& msg);
/// A heartbeat or a repair request: the kind known, `daemon` set exactly on a request, at most 1024 ranges, each
/// with a valid body name and 0 <= first <= last <= 2^62 (a request's first >= 1).
Decoded to_event(const sextant::fleet_control_t& msg);
/// Conversions event/output -> message, stamped with the sender's name and sequence number.
sextant::odometry_t to_message(const engine::Odometry& e, const std::string& sender, int64_t seq);
sextant::landmarks_t to_message(const engine::LandmarkSightings& e, const std::string& sender, int64_t seq);
sextant::bearing_scan_t to_message(const engine::BearingScan& e, const std::string& sender, int64_t seq);
sextant::loop_closure_t to_message(const engine::LoopClosure& e, const std::string& sender, int64_t seq);
sextant::imu_t to_message(const engine::ImuSample& e, const std::string& sender, int64_t seq);
sextant::gnss_t to_message(const engine::GnssFix& e, const std::string& sender, int64_t seq);
sextant::fused_pose_t to_message(const engine::FusedPose& o, const std::string& sender, int64_t seq);
sextant::geo_pose_t to_message(const engine::GeoPose& o, const std::string& sender, int64_t seq);
sextant::trajectory_t to_message(const engine::Trajectory& o, const std::string& sender, int64_t seq);
sextant::match_request_t to_message(const engine::MatchRequest& o, const std::string& sender, int64_t seq);
sextant::targets_t to_message(const engine::Targets& o, const std::string& sender, int64_t seq);
sextant::landmark_map_t to_message(const engine::LandmarkMap& o, const std::string& sender, int64_t seq);
sextant::fleet_contribution_t to_message(const engine::FleetContributions& o, const std::string& sender, int64_t seq);
sextant::fleet_control_t to_message(const engine::FleetControl& o, const std::string& sender, int64_t seq);
/// One contribution as fleet_item_t (fleet_exchange.hpp's item_bytes is its encoded size).
sextant::fleet_item_t to_item(const slam::GraphContribution::What& what);
/// Empty when `what`, encoded as fleet_item_t (to_item), passes every check to_event makes of a received
/// contribution; else the reason and the field ("covariance: fleet_item_t.anchors[0].covariance: not positive
/// semi-definite (...)").  The owner's check before it numbers a contribution (Outbox::set_wire_check).
std::string fleet_item_error(const slam::GraphContribution::What& what);

/// Message -> output (for replay reports, tests and `sextant listen`); no validation beyond decoding.
engine::FusedPose to_output(const sextant::fused_pose_t& m);
engine::GeoPose to_output(const sextant::geo_pose_t& m);
engine::Trajectory to_output(const sextant::trajectory_t& m);
engine::MatchRequest to_output(const sextant::match_request_t& m);
engine::Targets to_output(const sextant::targets_t& m);
engine::LandmarkMap to_output(const sextant::landmark_map_t& m);

}  // namespace sextant::runtime
