#pragma once
// The exchange between the graphs of a fleet's daemons (docs/graph.md "A fleet of daemons"): each daemon is fed only
// its own robots' sensors, makes graph contributions from them (estimators/slam/graph_contribution.hpp) and sends
// them on FLEET; every daemon applies the others' in each stream's order, so all hold the same fleet map.  This is
// the pure part: numbering, batching, loss repair, membership and ordering, with no I/O, no threads and no clock
// (every call that needs the time takes it, microseconds).  The graph stage owns one FleetExchange and saves it with
// its own state, so a restarted daemon asks only for what it missed.  Why in the engine: the exchange's state must
// be saved at the same moment as the graph it describes (what was applied, what was sent), which is the stage's.
//
// Streams.  A body is owned by the daemon that first contributes it; its contributions are numbered 1, 2, ... in the
// order its owner made them (the Outbox).  A receiver (the Inbox) applies stream (owner, body) in order: it holds
// back contributions that arrive early (at most reorder_window of them, reorder_bytes of wire size, per stream),
// drops what it already has, and finds gaps from a later contribution or from the owner's heartbeat (which names the
// stream's last number, so a lost tail is found too).  A gap is asked for (a REPAIR request to the owner) after
// repair_backoff_s, again after twice as long while nothing arrives (up to repair_backoff_max_s), from the start
// when the stream moves or a repair fills one of its holes.
//
// A restart: an owner restarted from its state directory continues from what it saved (the state is written every
// daemon.state_period_s).  What it sent after that save and before it stopped (killed, not stopped: SIGTERM saves
// the state at shutdown) was applied by the others and is not in its own graph, so before it contributes again it
// takes that tail back from them (TailFetch): every receiver keeps a copy of what it applied of each other member's
// streams (the newest `retain` of each, at most retain_mb, like the owner's log; not saved), and answers the
// restarted owner's request (a REPAIR to every member: its `daemon` is its sender) from it, at the repairs' rate.
// The owner takes the answers only from members, only for its own streams, in order from each stream's next number
// (duplicates from several answering members dropped; what a member holds ahead of a gap of its own is answered too
// and held), puts them back in its log as sent and applies them to its graph as its own (SlamGraph::adopt: its
// keyframe ids go on after the tail's); a number nobody gave back below one a member holds becomes kNothing, which
// changes no graph, so that member, asking for it, applies what the owner did.  Meanwhile it sends no heartbeat
// and its graph stage holds back what would make a contribution.  The wait ends restart_wait_s after the last of
// the tail arrived, or after the start when nothing comes (alone in the fleet, or nobody has more); then it goes on
// numbering after the tail, and the others see the stream go on where they have it.  What no receiver holds any more
// (all of them cut off, or more than `retain` behind) is not taken back: the owner's next numbers repeat those, and
// a receiver that applied them counts it (`owner_rewound`, from a heartbeat that ends the stream before what it
// heard).  The others' answers, heard by every daemon on the multicast, open no stream and change none
// (`repairs_overheard`), but for a daemon stuck on a gap of that stream (below).
//
// Relays: a repair does not depend on one path.  A receiver that asks an owner kRelayAfterAsks times in a row for the
// same number of a stream (its answers do not arrive, or its requests do not reach the owner) is heard asking by every
// member, and each member that holds a copy of that stream (the one it keeps for restarts) answers from it, within the
// same per-requester rate as its own repairs (`relayed`).  The receiver takes a repair of a stream from a member that
// is not its owner only while it is so stuck (`relays`); otherwise such answers are overheard as before.  A copy holds
// what its member applied of the owner's stream, the same contributions at the same numbers, so a relay is the
// owner's answer by another path.
//
// The limit of `retain`: the owner keeps the last `retain` contributions of each body (and at most retain_mb of them)
// to resend.  A receiver that misses older ones (cut off for longer, or a daemon that joins after the fleet made more
// than `retain` contributions of a body) counts them as lost (`lost`), and the stream resumes from the oldest one the
// owner still has: its map then lacks what was lost, and the later contributions that need a lost keyframe wait and
// are dropped by the graph as it drops any it cannot place.  Memory of the owner: a keyframe contribution takes
// about 740 bytes on the wire and in memory, a sighting 104 more; with 20000 retained keyframes and a few sightings
// each, about 20 MB per body, bounded by retain_mb in any case.
//
// Membership and hostile senders: only the configured members are heard (a sender not in `members` is refused,
// counted; this daemon's own messages, which multicast brings back, are ignored, counted); a body this daemon owns is
// never taken from a sender; a body owned by a member is not taken by another (counted, like
// daemon/runtime/source_claims.hpp); at most max_streams_per_sender streams per member; a number beyond the reorder
// window is dropped (counted; a repair fetches it when it is due); a repair request is answered with at most
// repair_bytes_per_s per requester (a token bucket of one second's worth).  The values themselves are validated by
// the codec (daemon/runtime/codec.hpp) before they get here.
#include "daemon/engine/fleet_events.hpp"
#include "daemon/engine/fleet_exchange_options.hpp"
#include "estimators/archive/binary_archive.hpp"

#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace sextant::engine {

namespace fleet {

using What = slam::GraphContribution::What;

/// The identified sightings of one contribution at most (fleet_item_t.num_sightings): a message's sightings beyond are
/// split into contributions of their own with the same anchor.
inline constexpr size_t kMaxSightingsPerItem = 256;
/// The keyframe ids of one KeyframesThinned contribution at most (fleet_item_t.num_keyframes): more are split likewise.
inline constexpr size_t kMaxThinnedPerItem = 1024;
/// The consecutive requests for the same number of a stream after which the other members answer from their copies
/// ("Relays" above), and after which the receiver takes such answers.
inline constexpr int kRelayAfterAsks = 3;
/// The contributions of one FLEET message, and the ranges of one FLEET_CONTROL message, at most.
inline constexpr size_t kMaxItemsPerMessage = 1024;
inline constexpr size_t kMaxRangesPerMessage = 1024;

/// The encoded size of one contribution as fleet_item_t (bytes), and of a FLEET message's fields around its
/// contributions (the fingerprint included); the codec's tests check both against lcm-gen's encoder.
size_t item_bytes(const What& what);
size_t message_overhead_bytes(const std::string& sender, const std::string& body);
/// `what` as it goes on the wire: a SightingsContribution of more than kMaxSightingsPerItem sightings becomes several,
/// in order, each with the same anchor, a KeyframesThinned of more than kMaxThinnedPerItem ids several; anything else
/// is itself.
std::vector<What> split_for_wire(const What& what);

/// One contribution with its number in its stream.
struct Numbered {
  int64_t seq = 0;
  What what;
  void save(archive::ArchiveWriter& w) const;
  void load(archive::ArchiveReader& r);
};

/// The newest contributions of one stream, oldest first and numbered without a gap: the owner's log it resends from,
/// and a receiver's copy of another owner's stream, from which it answers that owner's restart.  Bounded by
/// FleetExchangeOptions::retain (contributions) and retain_mb (wire size, item_bytes).
struct Retained {
  std::deque<Numbered> items;
  size_t bytes = 0;
  /// Appends the contribution numbered after the newest (the caller keeps the numbers contiguous).
  void push(Numbered n);
  /// Drops the oldest beyond the bounds, always keeping the newest `keep`; returns how many went.
  int64_t evict(const FleetExchangeOptions& o, size_t keep);
  void clear() {
    items.clear();
    bytes = 0;
  }
  /// The oldest and newest numbers held (0 when empty).
  int64_t first() const { return items.empty() ? 0 : items.front().seq; }
  int64_t last() const { return items.empty() ? 0 : items.back().seq; }
};

class Inbox;

struct OutboxCounters {
  int64_t contributions = 0;        // numbered (after splitting)
  int64_t messages = 0;             // FLEET messages made, first sendings
  int64_t evicted = 0;              // contributions no longer retained (retain, retain_mb)
  int64_t repair_requests = 0;      // REPAIR requests addressed to this daemon by a member
  int64_t repair_refused = 0;       // ... by a non-member, or for a body this daemon does not own
  int64_t repaired = 0;             // contributions resent
  int64_t repair_messages = 0;      // FLEET messages of resent contributions
  int64_t repair_limited = 0;       // contributions asked for and not resent for the requester's rate
  int64_t repair_not_retained = 0;  // contributions asked for that are no longer retained
  int64_t tail_requests = 0;        // restarted members' requests for their own streams' tails, answered from the
                                    // copies of those streams held here
  int64_t refused = 0;  // local contributions the wire's checks refuse, numbered as kNothing (Outbox::set_wire_check)
  int64_t relayed = 0;  // contributions of other owners' streams sent from the copies held here (Outbox::relay)
};

/// The sending side: numbers the contributions of the local bodies, keeps the last ones for repair, makes the FLEET
/// messages, the heartbeats, and the answers to repair requests.
class Outbox {
 public:
  Outbox(std::string self, FleetExchangeOptions options);

  /// Why a contribution would be refused by its receivers' decoder ("" when it would not): the daemon hands the
  /// codec's own checks (daemon/runtime/codec.hpp, fleet_item_error) here.
  using WireCheck = std::function<std::string(const What&)>;
  /// From now on, a contribution `check` refuses is numbered as kNothing (which changes no graph) and counted
  /// (`refused`), instead of going out as it is: every receiver's decoder would refuse the message that carries it,
  /// and its stream would stop there at every receiver for good.  None (the default): nothing is checked.
  void set_wire_check(WireCheck check) { wire_check_ = std::move(check); }
  /// Numbers a contribution of a local body (split as split_for_wire), keeps it and queues it for sending.
  void add(const slam::GraphContribution& c);
  /// Whether `body` is a local body (it contributed here).
  bool owns(const std::string& body) const { return streams_.contains(body); }
  /// This daemon's name (daemon.name).
  const std::string& self() const { return self_; }
  std::vector<std::string> bodies() const;
  /// The FLEET messages of what was added since the last call: per body, runs of consecutive contributions, each
  /// message at most max_message_bytes and kMaxItemsPerMessage contributions.
  std::vector<FleetContributions> take_messages(int64_t now_utime);
  /// The heartbeat when one is due (heartbeat_period_s since the last; the first at once): per local body the range
  /// retained and sent, kMaxRangesPerMessage bodies per message.  Nothing when not due or without a local body yet.
  std::vector<FleetControl> heartbeat(int64_t now_utime);
  /// The answer to a REPAIR request: the retained contributions asked for, as far as the requester's rate allows.
  /// A request addressed to another daemon is not for this one (nothing, not counted).
  std::vector<FleetContributions> answer(const FleetControl& request, int64_t now_utime);
  /// The answer to a restarted member's request for the tails of its own streams (a REPAIR whose `daemon` is its
  /// sender): what `copies` (this daemon's Inbox) applied of those streams and still holds, from the numbers asked,
  /// then what it holds ahead of a gap, within the same per-requester rate.  Nothing for a non-member (counted as refused) or this daemon itself.
  std::vector<FleetContributions> answer_tail(const FleetControl& request, const Inbox& copies, int64_t now_utime);
  /// A repair request from one member to another, overheard ("Relays" above): once the requester has asked for the
  /// same number of a stream kRelayAfterAsks times in a row, the answer from `copies` (this daemon's Inbox) for the
  /// ranges of that stream, within the requester's rate; nothing before, nor for a stream without a copy here.
  std::vector<FleetContributions> relay(const FleetControl& request, const Inbox& copies, int64_t now_utime);
  /// Takes back a contribution of a local body's stream that this daemon sent before it restarted from an older
  /// state (TailFetch): it must be numbered next_seq(body); it is retained as sent.  False (nothing changes) otherwise.
  bool adopt(const std::string& body, const Numbered& n);
  /// The numbers of `body`'s stream: the next to be given and the oldest retained (0: none).
  int64_t next_seq(const std::string& body) const;
  int64_t first_retained(const std::string& body) const;
  const OutboxCounters& counters() const { return counters_; }

  /// The numbering and the retained log of every local body, and the counters (not the rate buckets: a restarted
  /// daemon starts with full ones).  What was queued and not yet taken is saved as queued.
  void save(archive::ArchiveWriter& w) const;
  void load(archive::ArchiveReader& r);

 private:
  struct Stream {
    int64_t next_seq = 1;
    Retained retained;
    size_t pending = 0;  // the newest `pending` of `retained` are not sent yet
    void save(archive::ArchiveWriter& w) const;
    void load(archive::ArchiveReader& r);
  };
  struct Bucket {
    double tokens = 0;
    int64_t utime = 0;
  };
  /// Packs `items` of `body` (consecutive numbers) into messages.
  std::vector<FleetContributions> pack(const std::string& body, std::deque<Numbered>::const_iterator begin,
                                       std::deque<Numbered>::const_iterator end, bool repair, int64_t now) const;
  /// The bytes `requester` may be sent now (its bucket refilled to `now`).
  Bucket& bucket(const std::string& requester, int64_t now);
  void evict(Stream& s);
  /// One range of a repair request answered from `log` (up to its number `last`) into `out`, within the requester's
  /// bucket; `sent` counts the contributions sent.
  void answer_range(const FleetRange& range, const Retained& log, int64_t last, Bucket& b, int64_t now,
                    std::vector<FleetContributions>& out, int64_t& sent);

  std::string self_;
  FleetExchangeOptions options_;
  std::set<std::string> members_;
  std::map<std::string, Stream> streams_;
  std::map<std::string, Bucket> buckets_;  // per requester: members only
  /// Per (requester, body) overheard: the first number it asked for last and how many times in a row (relay); bodies
  /// of the streams copied here only, so bounded like them.
  std::map<std::pair<std::string, std::string>, std::pair<int64_t, int>> overheard_asks_;
  std::optional<int64_t> last_heartbeat_;
  OutboxCounters counters_;
  WireCheck wire_check_;
};

struct InboxCounters {
  int64_t messages = 0;           // FLEET messages from members, taken in
  int64_t delivered = 0;          // contributions handed to the graph, in their stream's order
  int64_t duplicates = 0;         // contributions already delivered or already held
  int64_t out_of_window = 0;      // contributions beyond the reorder window (dropped; a repair fetches them later)
  int64_t own = 0;                // messages of this daemon, brought back by multicast (ignored)
  int64_t not_member = 0;         // messages of a sender not in `members` (refused)
  int64_t local_body = 0;         // messages about a body this daemon owns (refused)
  int64_t claimed = 0;            // messages about a body another member owns (refused)
  int64_t too_many_streams = 0;   // messages that would open a stream beyond max_streams_per_sender (refused)
  int64_t lost = 0;               // contributions the owner no longer retained when asked for (skipped)
  int64_t repair_requests = 0;    // REPAIR requests made
  int64_t repair_asked = 0;       // contributions asked for in them
  int64_t heartbeats = 0;         // heartbeats of members taken in
  int64_t owner_rewound = 0;      // heartbeats, newer than every message heard of their stream, that end the stream
                                  // before what was heard (the owner restarted from a state older than what it had
                                  // sent and did not take its tail back: its next numbers repeat ones applied here)
  int64_t repairs_overheard = 0;  // resent contributions of a stream not known here from its owner, of another
                                  // member's stream, or of a local body (another daemon's repair or restart; ignored)
  int64_t relays = 0;             // repairs of a stream from a member that is not its owner, taken while stuck on a
                                  // gap of it (Outbox::relay)
};

/// The receiving side: per (owner, body) stream, the contributions in order.
class Inbox {
 public:
  Inbox(std::string self, FleetExchangeOptions options);

  /// `body` is this daemon's own (its sensors arrive here): no sender is heard about it from now on.  False when a
  /// member already contributed it (counted as claimed; the stream stays theirs).
  bool own(const std::string& body);
  /// A FLEET message: the contributions that are now next in their stream, in order (each with its body).
  std::vector<slam::GraphContribution> receive(const FleetContributions& m, int64_t now_utime);
  /// A heartbeat: learns each stream's last number (a lost tail becomes a gap) and the oldest the owner retains (what
  /// is older and missing is lost: the stream resumes, delivering what it held).  A REPAIR request is not for the
  /// Inbox (Outbox::answer): nothing.
  std::vector<slam::GraphContribution> receive(const FleetControl& m, int64_t now_utime);
  /// The REPAIR requests due now: one per owner with a gap whose back-off has passed, each range at most
  /// max_repair_range contributions (the first holes of the stream, at most kMaxRangesPerMessage ranges).
  std::vector<FleetControl> repair_requests(int64_t now_utime);

  /// The next number expected of `body`'s stream (1 for a stream not heard of) and its owner (empty: none).
  int64_t next_expected(const std::string& body) const;
  /// What was applied here of `body`'s stream and is still held (its newest, at most retain and retain_mb, since
  /// this daemon started: the copies are not saved), when `owner` owns it; nullptr otherwise.
  const Retained* copy_of(const std::string& body, const std::string& owner) const;
  /// The contributions of `body`'s stream held here ahead of a gap, by number, when `owner` owns it; nullptr otherwise.
  const std::map<int64_t, What>* held_of(const std::string& body, const std::string& owner) const;
  std::string owner(const std::string& body) const;
  /// Streams now, and contributions held ahead of their turn (all streams).
  size_t streams() const { return streams_.size(); }
  size_t held() const;
  const InboxCounters& counters() const { return counters_; }

  /// Every stream's owner, next number, known last and owner's first, the contributions held, the local bodies and
  /// the counters (not the repair timers: a restarted daemon asks for its gaps after repair_backoff_s).
  void save(archive::ArchiveWriter& w) const;
  void load(archive::ArchiveReader& r);

 private:
  struct Stream {
    std::string owner;
    int64_t next = 1;         // the next number to deliver
    int64_t known_last = 0;   // the highest number known to exist (held contributions, heartbeats)
    int64_t owner_first = 0;  // the oldest the owner retains (its last heartbeat)
    std::map<int64_t, What> held;
    size_t held_bytes = 0;
    int64_t ask_at = 0;  // when the gap may be asked for (0: no gap seen)
    double backoff_s = 0;
    int64_t sent_utime = 0;   // the owner's clock: its newest message (data or heartbeat) heard, for owner_rewound
    int64_t beat_last = 0;    // ... and the stream's last number it stated then
    int64_t heard_at = 0;     // this daemon's clock when the owner was last heard (not saved)
    int64_t asked_first = 0;  // the first number of the last repair request (not saved) ...
    int asks = 0;             // ... and how many requests in a row asked for it (0 once no gap is left)
    Retained copy;            // what was delivered, for the owner's restart (not saved)
    void save(archive::ArchiveWriter& w) const;
    void load(archive::ArchiveReader& r);
  };
  /// A repair message about a stream not known here from its sender, or about a local body: counted, ignored.
  bool overheard(const FleetContributions& m);
  /// A member's repair of another owner's stream while this daemon is stuck on a gap of it (its last kRelayAfterAsks
  /// requests asked for the same number; every message of a relayed answer is taken until it asks again): the
  /// stream; nullptr otherwise.
  Stream* relayed_stream(const FleetContributions& m);
  /// The contributions of `m` into `s`, and what is now next in it.  A repair that fills a hole, even one behind
  /// the stream's first gap, is progress: the gaps left are asked for again after repair_backoff_s, not after a
  /// back-off that grew while the first gap's answers were lost (the stream's next number may not move for a while
  /// when its first gap is the one whose answers are lost).
  std::vector<slam::GraphContribution> take(const FleetContributions& m, Stream& s, int64_t now);
  /// Whether `sender` may speak for `body` (counting why not); the stream when it may, opened if new.
  Stream* stream_for(const std::string& sender, const std::string& body);
  /// Delivers what is next in `s` into `out`, skipping (as lost) what is below the owner's first retained number.
  void deliver(const std::string& body, Stream& s, int64_t now, std::vector<slam::GraphContribution>& out);
  /// Keeps one contribution arriving at `seq` (held, duplicate or beyond the window); true when it filled a hole.
  bool hold(Stream& s, int64_t seq, What what);
  /// Schedules or clears `s`'s repair after the stream moved or learned of a gap.
  void schedule(Stream& s, int64_t now, bool moved);
  /// The gap of `s` (if any) asked for again after repair_backoff_s at the latest, the back-off back to its start.
  void ask_again_soon(Stream& s, int64_t now);
  /// The owner of `s` spoke (data or heartbeat).  After a silence longer than the back-off (a link healed, the owner
  /// restarted) a gap is asked for again at once, not at the end of a back-off that grew while nothing could arrive.
  void heard(Stream& s, int64_t now);
  /// The holes of `s` to ask for, at most max_repair_range contributions.
  std::vector<FleetRange> holes(const std::string& body, const Stream& s) const;

  std::string self_;
  FleetExchangeOptions options_;
  std::set<std::string> members_;
  std::set<std::string> local_;
  std::map<std::string, Stream> streams_;  // by body: a body has one owner
  std::map<std::string, int> streams_of_;  // streams per owner
  InboxCounters counters_;
};

struct TailCounters {
  int64_t requests = 0;      // requests for the tails of the own streams, sent to the fleet
  int64_t adopted = 0;       // contributions of the own streams taken back, in order, numbered as they were
  int64_t duplicates = 0;    // ... already taken (every member answers the same)
  int64_t out_of_order = 0;  // ... not continuing what was taken (dropped: asked for again)
  int64_t refused = 0;       // answers of a non-member, about a body this daemon does not own, or with bad numbers
                             // (this daemon's own repairs, which multicast brings back, are ignored, not counted)
  int64_t lost = 0;          // numbers no member gave back, below ones a member holds: filled with kNothing
};

/// What stands at a number of its own stream that a restarted owner could not take back while a member holds later
/// ones (that member lost it, and the owner died before resending it): a contribution that changes no graph (it thins
/// a keyframe id no body ever has), so that the owner and every member apply the same sequence after it.
inline const What kNothing = slam::KeyframesThinned{{INT64_MAX}};

/// A restarted owner taking the tails of its own streams back from the fleet ("A restart" above): one REPAIR request
/// to every member at once (its `daemon` is its sender), repeated with the repairs' back-off; the answers taken only
/// from members, only for the own streams, in order from each stream's next number (what comes ahead of it is held,
/// at most reorder_window per stream).  The wait ends restart_wait_s after the last contribution taken (or after the
/// start when none comes); what is still held then follows its numbers with kNothing in the holes.  Not saved.
class TailFetch {
 public:
  TailFetch(std::string self, FleetExchangeOptions options);
  /// Starts the wait for every stream of `outbox` (nothing to wait for without one, or without another member).
  void start(const Outbox& outbox);
  bool waiting() const { return waiting_; }
  /// The wait ends at the next call of requests(), whatever the time.
  void stop() { stop_ = true; }
  /// An answer (a FLEET message with repair set): the contributions that continue their stream from
  /// outbox.next_seq(body), in order; the caller adopts them (Outbox::adopt) before the next answer.
  std::vector<Numbered> receive(const FleetContributions& m, const Outbox& outbox, int64_t now_utime);
  /// The request due now (none, or one per kMaxRangesPerMessage streams), each range from the stream's next number
  /// and at most max_repair_range long.  When the wait is over (the first call starts its clock) it ends, and `ended`
  /// receives what was held ahead, per stream in order from its next number with kNothing in the holes, to adopt.
  std::vector<FleetControl> requests(const Outbox& outbox, int64_t now_utime,
                                     std::vector<std::pair<std::string, Numbered>>& ended);
  const TailCounters& counters() const { return counters_; }

 private:
  std::string self_;
  FleetExchangeOptions options_;
  std::set<std::string> members_;
  std::set<std::string> bodies_;
  /// The contributions held ahead of the stream's next number, in order from it with kNothing in the holes.
  std::vector<std::pair<std::string, Numbered>> fill_holes(const Outbox& outbox);
  std::map<std::string, std::map<int64_t, What>> ahead_;  // per stream, by number
  bool waiting_ = false, stop_ = false;
  int64_t quiet_until_ = 0;  // the wait's end (0: its clock not started)
  int64_t ask_at_ = 0;
  double backoff_s_ = 0;
  TailCounters counters_;
};

/// Both sides of one daemon, the unit the graph stage holds and saves.
struct FleetExchange {
  FleetExchange(const std::string& self, const FleetExchangeOptions& options)
      : outbox(self, options), inbox(self, options), tail(self, options) {}
  explicit FleetExchange(const FleetExchangeOptions& options) : FleetExchange(options.self, options) {}
  /// A contribution made from a local body's inputs: its body is local from now on, and it is numbered and queued.
  /// False (nothing sent) when another member already contributes that body (Inbox::own: the same robot fed to two
  /// daemons; counted as claimed).
  bool contributed(const slam::GraphContribution& c) {
    if (!inbox.own(c.body)) return false;
    outbox.add(c);
    return true;
  }
  /// A fleet event heard on the bus: the contributions now next in their streams, to apply in this order
  /// (SlamGraph::apply); for a repair request addressed to this daemon, a restarted member's request for its tails,
  /// or a request between two other members that this daemon relays, the messages that answer it, to send; while
  /// this daemon fetches its own tails, what it took back of them (already in the outbox), to apply as its own in this
  /// order (SlamGraph::adopt).
  struct Received {
    std::vector<slam::GraphContribution> apply;
    std::vector<FleetContributions> answers;
    std::vector<slam::GraphContribution> own;
  };
  Received received(const FleetContributions& m, int64_t now_utime);
  Received received(const FleetControl& m, int64_t now_utime);
  /// Whether this daemon, restarted, waits for the tails of its own streams (TailFetch): meanwhile it sends no
  /// heartbeat, and its graph makes no contribution (GraphStage holds its inputs back).
  bool fetching() const { return tail.waiting(); }
  /// The counters of both sides and the sizes now, named for the status channel (fleet_out_*, fleet_in_*).
  std::vector<std::pair<std::string, int64_t>> counters() const;
  /// What is due now: the FLEET messages queued, the heartbeat (or while fetching, the request for the tails) and the
  /// repair requests; when the fetch ends, what it held ahead of the streams (already in the outbox), to adopt in this
  /// order (SlamGraph::adopt).
  struct Due {
    std::vector<FleetContributions> contributions;
    std::vector<FleetControl> control;
    std::vector<slam::GraphContribution> own;
  };
  Due due(int64_t now_utime);
  void set_wire_check(Outbox::WireCheck check) { outbox.set_wire_check(std::move(check)); }
  void save(archive::ArchiveWriter& w) const {
    outbox.save(w);
    inbox.save(w);
  }
  /// A loaded exchange is a restarted daemon's: it starts fetching its own streams' tails.
  void load(archive::ArchiveReader& r) {
    outbox.load(r);
    inbox.load(r);
    tail.start(outbox);
  }

  Outbox outbox;
  Inbox inbox;
  TailFetch tail;
};

/// The contributions' own archive (every field, exactly), for the retained and held logs.
void save_what(archive::ArchiveWriter& w, const What& what);
void load_what(archive::ArchiveReader& r, What& what);

}  // namespace fleet
}  // namespace sextant::engine
