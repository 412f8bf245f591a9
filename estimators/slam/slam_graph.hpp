#pragma once
// Keyframe pose-graph SLAM with landmarks on the incremental smoother (estimators/graph/incremental_smoother.hpp), for
// any number of bodies, from plain inputs (slam_inputs.hpp).  The daemon's graph stage adapts it to the bus
// (daemon/engine/graph_stage.hpp); a program can call it directly.
//
// Per body (named by a string, e.g. the odometry source):
//  - keyframes (add_odometry): each odometry pose is classified by KeyframeSelector (too close / keyframe /
//    implausible jump, counted); a keyframe becomes a pose variable linked to the previous keyframe by the odometry
//    between them, with the composed increment covariance (estimators/lie/pose_covariance.hpp) as information.  The
//    first keyframe is held fixed at its odometry pose: the map frame is the odometry frame at the body's first
//    keyframe, as for dead reckoning.  A keyframe whose edge cannot enter the graph (a covariance that cannot be
//    inverted, or a value the smoother refuses) is dropped and counted; the selector goes back to the last keyframe
//    in the graph, so the next edge spans the dropped pose;
//  - after a real jump (KeyframeSelector's kReanchored: the odometry lost track and resumed elsewhere) the new keyframe
//    is linked to the last one before the jump by the odometry across it, its covariance inflated by the jump's own
//    size (jump_covariance.hpp).  One graph, not a new segment: a new segment would need its own gauge and map frame,
//    and loops across the two could not join them without moving a fixed pose; with a weak edge the map frame stays
//    and the first loops across the jump pull the new segment into place;
//  - loop proposals: for each new keyframe the LoopProposer's pairs go to SlamListener::loop_proposed (keyframe ids
//    are the body's keyframe indices 0, 1, 2, ...);
//  - loop closures (add_loop): tied to keyframes by id or by time (keyframe_track.hpp), gated against the current
//    estimate (loop_gate.hpp) and added with the robust kernel (DCS by default, its width per kind of body:
//    kernel_width_for); a loop about a time the odometry has not reached waits (at most 256 per body);
//  - landmark sightings (add_sightings): sightings with an id become point variables of the observing body (one per
//    id and body: each body's map has its own frame) and range/bearing factors on the keyframe before them
//    (sighting_model.hpp), gated when the landmark is known; sightings ahead of the odometry wait (at most
//    LandmarkOptions::max_waiting messages) for the odometry message after them, where the anchor's covariance is
//    exact (the covariance since the keyframe plus the interpolated part of the increment);
//  - lifelong mode (slam_graph_thinning.cpp): over a kind of body's keyframe budget the graph is thinned to the places
//    it needs, each map frame held where the whole graph had it (choose_anchors; LifelongOptions::hold_frame).
// One smoother per kind of body (planar, 3-D), created with the first such body (the robust kernel's width depends
// on the loops' dimension).  Every smoother update is reported to the listener, in order, while its estimates are
// current.  The smoother updates after every input, or with SlamOptions::solve_period_s at most once per period of a
// map frame's data time (what arrives between enters with the next update; flush() makes the one still owed).
//
// Fleet (slam_graph_fleet.cpp; FleetOptions): the bodies of one kind are one fleet.  Each body starts in a map
// frame of its own (named by the body; its first keyframe fixed).  Landmarks belong to a frame: bodies in one frame
// share them by id.  What connects two frames -- landmark ids both maps hold, a body's sighting of another body's
// marker (FleetOptions::markers), a loop closure between two bodies -- is evidence of their placement; when
// frame_placement.hpp's consensus rule places one frame in the other, they join: the frame whose root body's name
// comes later moves into the other (its variables transformed by the placement, its root's first keyframe freed,
// landmarks of the same id merged into one variable), and the evidence that agreed with the placement enters as
// factors (robot sightings: graph::PoseObservationFactor between the two bodies' keyframes; loops:
// RelativePoseFactor; both with the robust kernel); what disagreed is dropped and counted.  Within one frame, robot
// sightings and inter-robot loops become factors at once.  A frame is named by its root body (the smallest name);
// when the root is forgotten the next body names it and holds the gauge (its coordinates stay).
#include "estimators/archive/binary_archive.hpp"
#include "estimators/graph/incremental_smoother.hpp"
#include "estimators/keyframe/keyframe_selector.hpp"
#include "estimators/keyframe/loop_proposals.hpp"
#include "estimators/slam/graph_contribution.hpp"
#include "estimators/slam/keyframe_track.hpp"
#include "estimators/slam/slam_counters.hpp"
#include "estimators/slam/slam_inputs.hpp"
#include "estimators/slam/slam_options.hpp"

#include <limits>
#include <map>
#include <set>
#include <memory>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

namespace sextant::slam {

/// A keyframe of the graph: its id, time and current estimate in the body's map frame.
struct KeyframeEstimate {
  int64_t id = 0, utime = 0;
  SE3 pose;
};

/// A landmark of the graph's map: its id (the sightings' landmark id), position in the body's map frame (metres; z = 0
/// for planar bodies) and how many of its sightings are in the graph.
struct SlamLandmark {
  int64_t id = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  int64_t sightings = 0;
};

/// What the layer reports while it works (each call on the caller's thread, inside add_odometry / add_loop /
/// add_sightings, in the order things happen).
class SlamListener {
 public:
  virtual ~SlamListener() = default;
  /// A smoother update of `body` succeeded; `utime` is the newest time it covers (the newest keyframe's, or the
  /// keyframe's just added).  The estimates (keyframes(), newest_keyframe()) are this update's.
  virtual void updated(const std::string& body, int64_t utime, const graph::IncrementalStatus& status) = 0;
  /// A loop candidate for the new keyframe `a` (newest first) against the earlier keyframe `b`.
  virtual void loop_proposed(const std::string& body, int64_t utime, const KeyframeEstimate& a,
                             const KeyframeEstimate& b, bool random) = 0;
  /// An inter-robot candidate: the new keyframe `a` of `body` against keyframe `b` of `other`, a body of the same map
  /// frame whose estimate came within FleetOptions::proposal_radius.
  virtual void fleet_loop_proposed(const std::string& body, int64_t utime, const KeyframeEstimate& a,
                                   const std::string& other, const KeyframeEstimate& b) {
    (void)body, (void)utime, (void)a, (void)other, (void)b;
  }
  /// What a local body's inputs added to the graph, in the order it was added (graph_contribution.hpp): another
  /// SlamGraph that applies these builds the same graph.
  virtual void contributed(const GraphContribution& contribution) { (void)contribution; }
};

class SlamGraph {
 public:
  /// Throws std::invalid_argument for bad keyframe thresholds or loop proposal options.
  explicit SlamGraph(const SlamOptions& options);

  /// An odometry message of `body` (a new body starts with it; planar taken from it).  Older-or-equal times than the
  /// body's last are counted (odometry_out_of_order) and dropped.
  void add_odometry(const std::string& body, const OdometryInput& odometry, SlamListener& listener);
  /// A loop closure of `body` (see above).
  void add_loop(const std::string& body, const LoopInput& loop, SlamListener& listener);
  /// Landmark sightings of `body` (see above); nothing when landmarks are disabled.
  void add_sightings(const std::string& body, const SightingsInput& sightings, SlamListener& listener);
  /// The smoother updates that SlamOptions::solve_period_s is holding back, now (and reported): before the final
  /// estimates are read (the end of a replay, a daemon's shutdown).  Nothing when none is owed.
  void flush(SlamListener& listener);
  /// A contribution of a body whose inputs reach another graph (graph_contribution.hpp), in its stream's order: the
  /// back end builds from it what the owner's graph built.  A contribution about a body this graph has inputs of is
  /// refused (a body has one owner); a keyframe that does not follow the body's newest one, a sighting or loop on a
  /// keyframe that is not in the graph, values the smoother refuses: counted (SlamCounters::fleet_contributions_*),
  /// nothing else changes.  A whole robot sighting or inter-robot loop whose other body's keyframe has not arrived
  /// waits (at most FleetOptions::max_pending) and is applied when it does.  True when applied.
  bool apply(const GraphContribution& contribution, SlamListener& listener);
  /// Several contributions in their order (a FLEET message; a burst of repairs after a cut) as apply() takes them
  /// one by one, but with one smoother update per kind at the end instead of one per contribution: catching up on
  /// minutes of another robot's data costs a solve per message, not per keyframe and sighting.  A contribution whose
  /// gate reads the estimate (a loop, an inter-robot loop's half, a frame join) sees it solved first; frames are
  /// placed (try_joins) after the last update.  Returns how many were applied.
  int apply_all(const std::vector<GraphContribution>& contributions, SlamListener& listener);
  /// A contribution of a local body that this graph made before it was restarted from an older saved state (its
  /// tail, taken back from the graphs that applied it; daemon/engine/fleet_exchange.hpp), in its stream's order:
  /// applied as apply() applies a remote body's (not gated again, not contributed again: the others have it), and
  /// the body's front end goes on from it (the track and the keyframe selector at its newest keyframe; the next
  /// keyframe id after it; its inputs that waited for the odometry in the saved state and are not newer than it
  /// forgotten: the run that made it had handled them).  A half of a robot sighting or of an inter-robot loop adds
  /// nothing here: its whole is in the other body's stream.  A whole it had completed from another body's half is not
  /// completed again when that half is delivered again (this graph's state is older than it).  Refused (counted as
  /// apply() counts) for a remote body, or a new body's first contribution that is not a keyframe.  True when applied.
  bool adopt(const GraphContribution& contribution, SlamListener& listener);
  /// Whether a body's graph is built from contributions (another graph owns its inputs).
  bool remote(const std::string& body) const;
  /// Drops the body with its map: its keyframes, landmarks and their factors leave the smoother of its kind (rebuilt
  /// from the other bodies' variables and factors), its waiting loops and sightings go.
  void forget(const std::string& body);
  /// Refactorizes the smoothers from their graphs (after a failure the caller recovers from).
  void rebuild();

  /// The keyframe track of a body (nullptr: unknown body).
  const KeyframeTrack* track(const std::string& body) const;

  const SlamOptions& options() const { return options_; }
  const SlamCounters& counters() const { return counters_; }
  std::vector<std::string> bodies() const;
  /// The smoother of the planar bodies or of the 3-D ones (nullptr before the first such body).
  const graph::IncrementalSmoother* smoother(bool planar) const { return smoothers_[planar ? 1 : 0].get(); }
  /// The keyframes of a body (estimates), oldest first; empty for an unknown body.
  std::vector<KeyframeEstimate> keyframes(const std::string& body) const;
  /// The landmarks of a body's frame (estimates), by id.
  std::vector<SlamLandmark> landmarks(const std::string& body) const;
  /// The map frame a body's estimates are in: the name of its frame's root body (the body itself until it joins
  /// another's); empty for an unknown body.
  std::string frame_of(const std::string& body) const;
  /// The frames and their bodies (by frame name).
  std::map<std::string, std::vector<std::string>> frames() const;
  /// The newest keyframe of a body with its estimate and marginal covariance (6x6; a planar body's at x, y, yaw;
  /// zero when not determined).  The body must have a keyframe.
  struct NewestKeyframe {
    const TrackKeyframe* keyframe = nullptr;
    SE3 estimate;
    Matrix6d covariance = Matrix6d::Zero();
  };
  NewestKeyframe newest_keyframe(const std::string& body) const;
  /// Whether a body is planar (its smoother is the planar one); false for an unknown body.
  bool planar(const std::string& body) const;
  /// chi2 of the smoother a body's graph is in.
  double chi2(const std::string& body) const;
  /// The size of the graphs now (every body): keyframes and landmarks in them, factors in the smoothers.
  int64_t graph_keyframes() const;
  int64_t graph_landmarks() const;
  int64_t graph_factors() const;

  /// The state (slam_graph_state.cpp): both graphs (variables at their estimates, factors with their kernels), every
  /// body's track, selector, waiting loops and sightings and landmarks, next ids and counters.  Saving refactorizes
  /// each smoother from its graph (rebuild) right after writing it, and forgets the sighting gate's cached marginals:
  /// a layer restored from the bytes does the same from the same graph, so both continue identically.  load() throws
  /// std::logic_error into a used layer and archive::ArchiveError for bytes that do not describe a consistent state.
  void save(archive::ArchiveWriter& w);
  void load(archive::ArchiveReader& r);

 private:
  static constexpr int64_t kNever = std::numeric_limits<int64_t>::min();
  /// The fleet's part of load(): frames checked against the bodies, the pending links (slam_graph_state.cpp).
  void load_fleet(archive::ArchiveReader& r);
  /// What a factor of a smoother is, kept beside it (one tag per factor, in the smoother's order) so that lifelong
  /// thinning and forgetting can rebuild the graph: odometry edges are recomposed, loops and sightings carried over.
  enum class FactorRole { kOdometry, kLoop, kSighting };
  struct FactorTag {
    FactorRole role = FactorRole::kOdometry;
    bool robust = false;
    std::optional<double> kernel_width;
  };
  struct Landmark {
    int variable = -1;
    int64_t sightings = 0;
  };
  struct Body {
    bool remote = false;  // built from contributions (apply), not from inputs
    std::string frame;    // the root body of its map frame (slam_graph_fleet.cpp); landmarks live in the root's Body
    bool planar = false;
    graph::IncrementalSmoother* smoother = nullptr;  // smoothers_[planar]
    KeyframeSelector selector;
    KeyframeTrack track;
    std::vector<LoopInput> early_loops;           // about times the odometry has not reached yet (bounded)
    std::vector<SightingsInput> early_sightings;  // ahead of the odometry, in time order (bounded)
    std::map<int64_t, Landmark> landmarks;        // by landmark id; a frame's map, kept by its root body only
    std::vector<std::pair<std::string, BodyLoopHalf>> early_halves;    // other bodies' loops (from, half) to a time
                                                                       // this one's odometry has not reached
    std::vector<std::pair<std::string, BodySightingHalf>> early_seen;  // sightings of this body (observer, half)
                                                                       // ahead of its odometry
    std::set<int64_t> owner_thinned;  // a remote body's keyframes its owner thinned, taken out at the next thinning
    // Solve cadence, kept by a frame's root body for the whole frame (its bodies share one estimate): the newest
    // local input's data time, and that clock at the frame's last reported update (us).
    int64_t clock = kNever, reported = kNever;
  };
  /// A body's sighting of another body's marker, anchored on a keyframe of each (by keyframe id: thinning renumbers
  /// positions) with the odometry motion from it to the sighting's time and that motion's covariance.
  struct SightingLink {
    std::string observer, observed;
    int64_t utime = 0;
    SE3 sensor_in_body;
    LandmarkSighting sighting;
    int64_t observer_keyframe = 0, observed_keyframe = 0;
    SE3 observer_motion, observed_motion;
    Matrix6d observer_covariance = Matrix6d::Zero(), observed_covariance = Matrix6d::Zero();
    template <class Archive, class Self>
    static void fields(Archive& a, Self& s) {
      a(s.observer)(s.observed)(s.utime)(s.sensor_in_body)(s.sighting)(s.observer_keyframe)(s.observed_keyframe)(
          s.observer_motion)(s.observed_motion)(s.observer_covariance)(s.observed_covariance);
    }
  };
  /// A loop between keyframes of two bodies (loop_gate.hpp's KeyframeLoop, by keyframe id).
  struct LoopLink {
    std::string from, to;
    int64_t from_keyframe = 0, to_keyframe = 0;
    SE3 z;
    Matrix6d information = Matrix6d::Zero();
    template <class Archive, class Self>
    static void fields(Archive& a, Self& l) {
      a(l.from)(l.to)(l.from_keyframe)(l.to_keyframe)(l.z)(l.information);
    }
  };
  /// Robot sightings and loops between two frames not joined yet, kept as evidence of their placement (oldest first,
  /// at most FleetOptions::max_pending of each).
  struct Pending {
    std::vector<SightingLink> sightings;
    std::vector<LoopLink> loops;
  };

  Body& body_for(const std::string& name, bool planar);
  graph::IncrementalSmoother& smoother_for(bool planar);
  /// Adds a factor to the body's smoother and its tag (throws what the smoother throws, and then adds no tag).
  void add_factor(Body& b, std::unique_ptr<graph::Factor> factor, FactorRole role, bool robust,
                  std::optional<double> width);
  SE3 estimate(const Body& b, int variable) const;
  /// estimate(b, variable).translation(), cheaper (no rotation formed).
  Eigen::Vector3d position(const Body& b, int variable) const;
  void on_keyframe_candidate(const std::string& name, Body& b, const OdometryInput& o, SlamListener& listener);
  /// The sightings of body `b` that waited for its odometry (early_seen) and are now behind it: anchored.
  void complete_seen(Body& b, SlamListener& listener);

  // The back end (slam_graph_contributions.cpp): what one contribution adds, the same for a local body's (made by the
  // front end just before) and a remote one's.  Each returns whether a factor entered; the caller solves.
  /// A keyframe and its odometry edge; for a local body, what follows a new keyframe (update, proposals, thinning).
  bool add_keyframe_to_graph(const std::string& name, Body& b, const KeyframeContribution& k, SlamListener& listener);
  /// The landmark sightings of one message at `anchor` (slam_graph_sightings.cpp), markers left out; gated against
  /// the estimate and the accepted ones appended to `accepted` when it is given (the owner), taken as they are when
  /// not (a remote body's, gated by its owner).  A known landmark not solved yet (an update owed) is solved first.
  bool add_landmark_sightings(Body& b, const SightingsInput& s, const TrackPoint& anchor, SightingsInput* accepted,
                              SlamListener& listener);
  /// The observed body's end of a robot sighting when that body is local: anchored, contributed and added.
  bool complete_body_sighting(const std::string& observer, const BodySightingHalf& h, SlamListener& listener);
  /// Whether a loop's ends, landed at `from` and `to`, are known well enough for the gate to check it
  /// (landing_sigma within loop_max_landing_sigma); a loop that is not is counted as rejected.
  bool landing_checkable(const TrackPoint& from, const TrackPoint& to);
  /// A same-body loop on keyframes, gated when the body is local (its owner's gate otherwise).
  bool add_loop_on_keyframes(Body& b, const LoopContribution& l);
  /// The "to" body's end of an inter-robot loop when that body is local (it may wait for its odometry).
  bool complete_body_loop(const std::string& from, const BodyLoopHalf& h, SlamListener& listener);
  /// A whole robot sighting or inter-robot loop (c.body the observed / "to" body): a factor when both bodies share a
  /// frame, else evidence for their placement; it waits when a keyframe it names has not arrived.
  bool add_whole(const GraphContribution& c);
  /// Before the first keyframe of a loop's time: the loop waits for the odometry (bounded per body).
  void wait_for_odometry(Body& b, const LoopInput& l);
  /// The time of body `name`'s own odometry a loop needs to have reached: both ends within the body, else its own end.
  static int64_t own_time(const std::string& name, const LoopInput& l);
  /// The inputs of body `name` that waited for its odometry in the saved state and are not newer than `utime`, the
  /// time of a contribution taken back (adopt): the run before the restart handled them (its odometry had passed
  /// that time), and what they made is in the tail taken back; they are forgotten, not handled twice.
  void forget_handled_before_restart(const std::string& name, Body& b, int64_t utime);
  /// A whole robot sighting or loop whose other body's keyframe is not in the graph yet waits (bounded); retried
  /// after every keyframe.
  bool keyframes_present(const GraphContribution& c) const;
  void wait_for_keyframes(const GraphContribution& c);
  void retry_waiting(SlamListener& listener);
  /// One contribution through the back end, for a remote body (apply) or a completed whole: the update after it.
  bool apply_contribution(const GraphContribution& c, SlamListener& listener);
  std::optional<TrackPoint> point_of(const Body& b, const KeyframeAnchor& a) const;
  KeyframeAnchor anchor_of(const Body& b, const TrackPoint& p) const;
  /// A keyframe candidate that cannot enter the graph (its odometry edge's covariance cannot be inverted, or the
  /// smoother refuses it): counted; the selector goes back to the body's last keyframe in the graph, so the next
  /// keyframe is measured from that one and its edge, which spans the dropped pose, accumulates from there.
  void drop_keyframe(Body& b);
  void propose_loops(const std::string& name, const Body& b, int64_t utime, SlamListener& listener);
  /// For the newest keyframe of `name`: each other body of its frame's nearest keyframe within proposal_radius.
  void propose_fleet_loops(const std::string& name, const Body& b, int64_t utime, SlamListener& listener);
  /// One smoother update, counted.
  graph::IncrementalStatus solve(graph::IncrementalSmoother& smoother);
  /// The updates, frame updates and placements asked for and not done yet, done by run_deferred once for all: while
  /// apply_all runs (`active`), and between local inputs while SlamOptions::solve_period_s holds the updates back.
  struct Deferred {
    bool active = false;                     // apply_all's batch
    bool dirty[2] = {false, false};          // per kind: a smoother update is owed
    std::map<std::string, int64_t> updated;  // body -> the time its update was asked for at
    std::set<std::string> frames, joins;     // frames whose bodies are reported; frames whose placement is tried
  };
  /// The smoother updates owed (one per kind), reported as update() and update_frame() would have, then the
  /// placements; apply_all's batch goes on afterwards.  `all` false: the reports of frames still within their solve
  /// period stay owed (a solve to read the estimate, not to publish it).
  void run_deferred(SlamListener& listener, bool all = true);
  /// One smoother update for `b`, counted and reported when it succeeds: now, or owed (run_deferred) during
  /// apply_all's batch or while solve_period_s holds it back.
  void update(const std::string& name, Body& b, int64_t utime, SlamListener& listener);
  /// Solve cadence (SlamOptions::solve_period_s), per map frame: an update asked for while a local input is handled
  /// waits when `b`'s frame was reported less than the period ago in its data time; contributions (apply) update at
  /// once.  Frames apart stay apart: another frame's inputs never move when this one's updates are reported.
  bool waits_for_period(const Body& b) const;
  bool owes() const { return deferred_.dirty[0] || deferred_.dirty[1]; }
  /// A gate is about to read an estimate that an owed update has not solved yet: the update is made now (reported to
  /// the frames whose period has passed; the others' reports stay owed).  Nothing during apply_all's batch.
  void solve_owed(SlamListener& listener);
  /// Whether an update report is owed to a body of `frame`.
  bool frame_owes(const std::string& frame) const;
  /// A local input of `body` at `utime`, before it is handled: its frame's clock.
  void begin_local_input(const std::string& body, int64_t utime);
  /// After it: the frame's clock again (a new body's frame exists now), and its owed update once the period passed.
  void end_local_input(int64_t utime, SlamListener& listener);
  /// add_odometry, add_loop and add_sightings themselves, between begin_local_input and end_local_input.
  void handle_odometry(const std::string& name, const OdometryInput& o, SlamListener& listener);
  void handle_loop(const std::string& name, const LoopInput& l, SlamListener& listener);
  void handle_sightings(const std::string& name, const SightingsInput& s, SlamListener& listener);
  /// The sighting gate's marginal of the keyframe at `index` of `b`'s track: a keyframe not solved yet (an update
  /// owed) takes the marginal of the newest solved keyframe before it, a little narrower than its own would be.
  Eigen::MatrixXd keyframe_gate_marginal(const Body& b, size_t index);
  /// The sightings of one message at `anchor` (slam_graph_sightings.cpp): landmarks and markers, contributed.
  void add_anchored_sightings(const std::string& name, Body& b, const SightingsInput& s, const TrackPoint& anchor,
                              SlamListener& listener);
  /// Marginal covariances for the sighting gate, reused for kGateMarginalUpdates updates.
  Eigen::MatrixXd gate_marginal(const Body& b, int variable);
  /// A new smoother of `kind` from `vars` (the old graph's variables, possibly moved): variable v is dropped when
  /// merge_into[v] == kDropVariable, merged into variable merge_into[v] when >= 0, else kept; factors on a dropped
  /// variable leave, the others follow their variables, in their old order (slam_graph_state.cpp).
  static constexpr int kDropVariable = -2;
  struct Rebuilt {
    std::unique_ptr<graph::IncrementalSmoother> smoother;
    std::vector<FactorTag> tags;
    std::vector<int> remap;  // old variable -> new (-1: dropped)
  };
  Rebuilt rebuilt(int kind, const std::vector<graph::Variable>& vars, const std::vector<int>& merge_into) const;
  /// Puts a rebuilt smoother in place: every body of the kind on its new variables.
  void commit_rebuilt(int kind, Rebuilt r);
  /// Before a frame's root is forgotten: the next body of the frame (by name) becomes its root, with its landmarks
  /// and the gauge; returns that body's name (empty when the root was alone).
  std::string hand_over_frame(const std::string& root);
  /// Marks for dropping (and removes from their maps) the landmarks no factor would be left on once the variables
  /// marked kDropVariable go: a landmark only a forgotten body saw.
  void drop_unseen_landmarks(int kind, std::vector<int>& merge_into);

  // Fleet (slam_graph_fleet.cpp).
  Body& root_of(const Body& b) { return bodies_.at(b.frame); }
  const Body& root_of(const Body& b) const { return bodies_.at(b.frame); }
  /// A loop of `name` whose "to" end is another body's.
  void add_body_loop(const std::string& name, Body& b, const LoopInput& l, SlamListener& listener);
  bool add_sighting_factor(const SightingLink& s);
  bool add_loop_factor(const LoopLink& l);
  /// The placement evidence between frames `a` and `b` (T_ab) and which pending item each came from.
  struct Evidence;
  Evidence evidence_between(const std::string& a, const std::string& b);
  /// Tries to place frame `b` in `a` (or the reverse) and joins them when the rule holds; true when joined.  Only the
  /// owner of the moving frame's root decides (graph_contribution.hpp, FrameJoin): it contributes its decision.
  bool try_join(const std::string& a, const std::string& b, SlamListener& listener);
  /// Joins frame `gone` into `keep` at `keep_from_gone`: the evidence `ev` between them leaves the pending lists,
  /// the items flagged in `inlier` become factors and the others count as outliers; the variables move; solved.
  void join_frames(const std::string& keep, const std::string& gone, const SE3& keep_from_gone, const Evidence& ev,
                   const std::vector<char>& inlier, SlamListener& listener);
  /// Another graph's decision that the frame of remote root `gone` joins (false when it cannot apply here: `gone`
  /// is no frame's root, or the kept frame's root is unknown or of the other kind).
  bool apply_join(const std::string& gone, const FrameJoin& j, SlamListener& listener);
  /// Where frame `frame` is now: the root of the frame it moved into by joins since (itself when it never moved) and
  /// the placement of its old coordinates there.
  std::pair<std::string, SE3> current_frame(const std::string& frame) const;
  /// Moves the frame `gone`'s variables into `keep` and rebuilds the smoother (landmarks of one id merged).
  void merge_frame_variables(const std::string& keep, const std::string& gone, const SE3& keep_from_gone);
  /// After a join or a new link: a smoother update reported for every body of the frame.
  void update_frame(const std::string& frame, SlamListener& listener);
  /// The frame roots other than `frame` that share evidence with it (pending links or landmark ids).
  std::vector<std::string> linked_frames(const std::string& frame) const;
  void try_joins(const std::string& frame, SlamListener& listener);

  /// Lifelong thinning (slam_graph_thinning.cpp): over the kind's budget, rebuild the smoother of that kind with the
  /// keyframes keyframes_to_keep() keeps (estimators/keyframe/keyframe_thinning.hpp): odometry composed across the
  /// thinned ones, loops and sightings of thinned keyframes dropped, landmarks left without sightings dropped; each
  /// map frame's gauge stays on its root's first keyframe while kept measurements determine it, else moves to its
  /// best-tied settled keyframe, fixed at its current estimate (choose_anchors).
  /// A local body's thinned keyframes are contributed (KeyframesThinned); a remote body's are its owner's.
  void maybe_thin(bool planar, SlamListener& listener);
  void thin(bool planar, SlamListener& listener);
  /// A remote body's keyframes that stay at a thinning: all but those its owner thinned (never its newest).
  std::vector<char> owner_kept(const Body& b) const;
  /// thin's steps (slam_graph_thinning.cpp), on the plan they fill in turn.
  struct ThinningPlan;
  bool choose_kept_keyframes(ThinningPlan& p);
  void choose_kept_factors(ThinningPlan& p);
  void choose_anchors(ThinningPlan& p);
  void rebuild_smoother(ThinningPlan& p);
  void commit_thinning(ThinningPlan& p);

  SlamOptions options_;
  LoopProposer proposer_;
  std::unique_ptr<graph::IncrementalSmoother> smoothers_[2];  // [0] 3-D, [1] planar
  std::vector<FactorTag> factor_tags_[2];                     // per smoother, per factor
  static constexpr int64_t kGateMarginalUpdates = 25;
  static constexpr size_t kGateMarginalSteps = 16;  // keyframes keyframe_gate_marginal looks back at most
  std::map<int, std::pair<int64_t, Eigen::MatrixXd>>
      gate_marginals_[2];  // per variable: (updates when computed, marginal)
  int64_t keyframes_since_thinning_[2] = {0, 0};
  std::map<std::string, Body> bodies_;
  Pending pending_;
  std::vector<GraphContribution> waiting_wholes_;  // robot sightings and loops waiting for a keyframe (oldest first)
  /// The robot sightings and inter-robot loops this graph completed before it restarted and took back (adopt): the
  /// other body's half, delivered again since (the restarted graph's inputs are older than it), is not completed
  /// twice.  At most one per contribution taken back; not saved.
  using WholeKey = std::tuple<int, std::string, std::string, int64_t, int64_t>;
  static WholeKey whole_key(const GraphContribution& whole);
  /// Whether `whole` was taken back (and is forgotten now): then it is neither contributed nor added again.
  bool completed_before_restart(const GraphContribution& whole) { return adopted_wholes_.erase(whole_key(whole)) > 0; }
  std::set<WholeKey> adopted_wholes_;
  std::map<std::pair<std::string, std::string>, int64_t> join_attempts_;  // frame pair -> keyframes at the last try
  std::map<std::string, std::pair<std::string, SE3>> moved_frames_;       // a joined frame -> (into, into_from_it)
  Deferred deferred_;
  bool local_input_ = false;  // a local input is being handled ...
  std::string input_body_;    // ... of this body
  int64_t input_utime_ = 0;   // ... at this data time
  int64_t next_variable_id_ = 0;
  double loop_gate_[2] = {0, 0}, sighting_gate_[2] = {0, 0};  // chi-square thresholds, [0] 3-D, [1] planar
  double sighting_width_[2] = {0, 0};                         // sighting_kernel_width_for
  SlamCounters counters_;
};

}  // namespace sextant::slam
