// The exchange (fleet_exchange.hpp): the wire sizes of a contribution, its splitting, the archive of a numbered one,
// and both sides together (the Outbox: fleet_outbox.cpp; the Inbox: fleet_inbox.cpp).
#include "daemon/engine/fleet_exchange.hpp"

#include "estimators/lie/lie_archive.hpp"

#include <algorithm>
#include <type_traits>

namespace sextant::engine::fleet {
namespace {

using namespace slam;

// What fleet_item_t carries of a contribution: the other body's name and how many poses, anchors and sightings.
struct Shape {
  size_t other = 0, poses = 0, anchors = 0, sightings = 0, keyframes = 0;
};

Shape shape_of(const What& what) {
  return std::visit(
      [](const auto& x) -> Shape {
        using T = std::decay_t<decltype(x)>;
        if constexpr (std::is_same_v<T, KeyframeContribution>)
          return {0, x.first ? size_t{1} : size_t{2}, 0, 0};
        else if constexpr (std::is_same_v<T, SightingsContribution>)
          return {0, 1, 1, x.sightings.sightings.size()};
        else if constexpr (std::is_same_v<T, BodySightingHalf>)
          return {x.observed.size(), 1, 1, 1};
        else if constexpr (std::is_same_v<T, BodySighting>)
          return {x.observer.size(), 1, 2, 1};
        else if constexpr (std::is_same_v<T, LoopContribution>)
          return {0, 1, 0, 0};
        else if constexpr (std::is_same_v<T, BodyLoopHalf>)
          return {x.loop.body_to.size(), 1, 1, 0};
        else if constexpr (std::is_same_v<T, FrameJoin>)
          return {x.keep.size(), 1, 0, 0};
        else if constexpr (std::is_same_v<T, KeyframesThinned>)
          return {0, 0, 0, 0, x.keyframes.size()};
        else
          return {x.from.size(), 1, 0, 0};
      },
      what);
}

}  // namespace

size_t item_bytes(const What& what) {
  // fleet_item_t: kind, flags (1 + 1), utime, utime_to (8 + 8), planar (1), other (4 + n + 1), keyframe_a, keyframe_b
  // (8 + 8), four counts (4 each); a fleet_pose_t is 43 doubles, a fleet_anchor_t 44 values of 8 bytes, a
  // landmark_observation_t 13, a keyframe id 8.
  const Shape s = shape_of(what);
  return 56 + s.other + 344 * s.poses + 352 * s.anchors + 104 * s.sightings + 8 * s.keyframes;
}

size_t message_overhead_bytes(const std::string& sender, const std::string& body) {
  // The fingerprint (8), utime (8), sender (4 + n + 1), seq (8), body (4 + n + 1), repair (1), first (8), the count (4).
  return 47 + sender.size() + body.size();
}

std::vector<What> split_for_wire(const What& what) {
  if (const auto* t = std::get_if<KeyframesThinned>(&what)) {
    std::vector<What> parts;
    for (size_t i = 0; i < t->keyframes.size(); i += kMaxThinnedPerItem) {
      const auto from = t->keyframes.begin() + static_cast<std::ptrdiff_t>(i);
      const auto n = static_cast<std::ptrdiff_t>(std::min(kMaxThinnedPerItem, t->keyframes.size() - i));
      parts.push_back(KeyframesThinned{{from, from + n}});
    }
    return parts;
  }
  const auto* s = std::get_if<SightingsContribution>(&what);
  if (s == nullptr) return {what};
  const auto& all = s->sightings.sightings;
  std::vector<What> parts;
  for (size_t i = 0; i < all.size(); i += kMaxSightingsPerItem) {
    SightingsContribution part;
    part.anchor = s->anchor;
    part.sightings.utime = s->sightings.utime;
    part.sightings.planar = s->sightings.planar;
    part.sightings.sensor_in_body = s->sightings.sensor_in_body;
    const auto from = all.begin() + static_cast<std::ptrdiff_t>(i);
    part.sightings.sightings.assign(from,
                                    from + static_cast<std::ptrdiff_t>(std::min(kMaxSightingsPerItem, all.size() - i)));
    parts.push_back(std::move(part));
  }
  return parts;  // none for a contribution without sightings: it adds nothing to a graph
}

// A contribution's archive is its own (graph_contribution.hpp: the alternative's index, then its fields).
void Numbered::save(archive::ArchiveWriter& w) const { w(seq)(what); }

void Numbered::load(archive::ArchiveReader& r) { r(seq)(what); }

std::vector<std::pair<std::string, int64_t>> FleetExchange::counters() const {
  const OutboxCounters& o = outbox.counters();
  const InboxCounters& i = inbox.counters();
  const TailCounters& t = tail.counters();
  return {{"fleet_out_contributions", o.contributions},
          {"fleet_out_messages", o.messages},
          {"fleet_out_evicted", o.evicted},
          {"fleet_out_repair_requests", o.repair_requests},
          {"fleet_out_repair_refused", o.repair_refused},
          {"fleet_out_repaired", o.repaired},
          {"fleet_out_repair_messages", o.repair_messages},
          {"fleet_out_repair_limited", o.repair_limited},
          {"fleet_out_repair_not_retained", o.repair_not_retained},
          {"fleet_in_messages", i.messages},
          {"fleet_in_delivered", i.delivered},
          {"fleet_in_duplicates", i.duplicates},
          {"fleet_in_out_of_window", i.out_of_window},
          {"fleet_in_own", i.own},
          {"fleet_in_not_member", i.not_member},
          {"fleet_in_local_body", i.local_body},
          {"fleet_in_claimed", i.claimed},
          {"fleet_in_too_many_streams", i.too_many_streams},
          {"fleet_in_lost", i.lost},
          {"fleet_in_repair_requests", i.repair_requests},
          {"fleet_in_repair_asked", i.repair_asked},
          {"fleet_in_heartbeats", i.heartbeats},
          {"fleet_in_owner_rewound", i.owner_rewound},
          {"fleet_in_repairs_overheard", i.repairs_overheard},
          {"fleet_out_tail_requests", o.tail_requests},
          {"fleet_out_refused", o.refused},
          {"fleet_out_relayed", o.relayed},
          {"fleet_in_relays", i.relays},
          {"fleet_tail_requests", t.requests},
          {"fleet_tail_adopted", t.adopted},
          {"fleet_tail_duplicates", t.duplicates},
          {"fleet_tail_out_of_order", t.out_of_order},
          {"fleet_tail_refused", t.refused},
          {"fleet_tail_lost", t.lost},
          {"fleet_tail_waiting", fetching() ? 1 : 0},
          {"fleet_in_streams", static_cast<int64_t>(inbox.streams())},
          {"fleet_in_held", static_cast<int64_t>(inbox.held())}};
}

FleetExchange::Received FleetExchange::received(const FleetContributions& m, int64_t now_utime) {
  if (!(fetching() && m.repair && outbox.owns(m.body))) return {inbox.receive(m, now_utime), {}, {}};
  Received r;
  for (Numbered& n : tail.receive(m, outbox, now_utime)) {
    outbox.adopt(m.body, n);  // numbered next by TailFetch
    r.own.push_back(slam::GraphContribution{m.body, std::move(n.what)});
  }
  return r;
}

FleetExchange::Received FleetExchange::received(const FleetControl& m, int64_t now_utime) {
  if (m.kind != FleetControl::Kind::kRepair) return {inbox.receive(m, now_utime), {}, {}};
  if (m.daemon == m.sender) return {{}, outbox.answer_tail(m, inbox, now_utime), {}};
  if (m.daemon != outbox.self()) return {{}, outbox.relay(m, inbox, now_utime), {}};
  return {{}, outbox.answer(m, now_utime), {}};
}

FleetExchange::Due FleetExchange::due(int64_t now_utime) {
  Due d;
  d.contributions = outbox.take_messages(now_utime);
  // While the tails are fetched the heartbeat waits: it would state the streams as this daemon's saved state ends
  // them, before what the others hold.
  std::vector<std::pair<std::string, Numbered>> ended;
  d.control = tail.requests(outbox, now_utime, ended);
  for (auto& [body, n] : ended) {
    outbox.adopt(body, n);  // numbered next by TailFetch
    d.own.push_back(slam::GraphContribution{body, std::move(n.what)});
  }
  if (!fetching())
    for (FleetControl& h : outbox.heartbeat(now_utime)) d.control.push_back(std::move(h));
  for (FleetControl& r : inbox.repair_requests(now_utime)) d.control.push_back(std::move(r));
  return d;
}

}  // namespace sextant::engine::fleet
