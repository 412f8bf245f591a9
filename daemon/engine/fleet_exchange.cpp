#include "daemon/engine/fleet_exchange.hpp"

#include "estimators/lie/lie_archive.hpp"

#include <algorithm>
#include <limits>
#include <type_traits>

namespace sextant::engine::fleet {
namespace {

using namespace slam;

constexpr size_t kMegabyte = size_t{1} << 20;
// A stream's numbers stay far from overflow: a sender's `first` + count beyond this is out of any window.
constexpr int64_t kMaxSeq = int64_t{1} << 62;

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

template <class A, class C>
void outbox_counter_fields(A& a, C& c) {
  a(c.contributions)(c.messages)(c.evicted)(c.repair_requests)(c.repair_refused)(c.repaired)(c.repair_messages)(
      c.repair_limited)(c.repair_not_retained);
}

template <class A, class C>
void inbox_counter_fields(A& a, C& c) {
  a(c.messages)(c.delivered)(c.duplicates)(c.out_of_window)(c.own)(c.not_member)(c.local_body)(c.claimed)(
      c.too_many_streams)(c.lost)(c.repair_requests)(c.repair_asked)(c.heartbeats)(c.owner_rewound);
}

int64_t micros(double seconds) { return static_cast<int64_t>(seconds * 1e6); }

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

// ---- Outbox ----------------------------------------------------------------------------------------------------

Outbox::Outbox(std::string self, FleetExchangeOptions options)
    : self_(std::move(self)),
      options_(std::move(options)),
      members_(options_.members.begin(), options_.members.end()) {}

void Outbox::add(const slam::GraphContribution& c) {
  Stream& s = streams_[c.body];
  for (What& what : split_for_wire(c.what)) {
    s.retained_bytes += item_bytes(what);
    s.retained.push_back(Numbered{s.next_seq++, std::move(what)});
    ++s.pending;
    ++counters_.contributions;
  }
  evict(s);
}

void Outbox::evict(Stream& s) {
  const size_t max_count = static_cast<size_t>(std::max(options_.retain, 0));
  const size_t max_bytes = static_cast<size_t>(std::max(options_.retain_mb, 0)) * kMegabyte;
  // What is not sent yet stays (it goes with the next take_messages, then may go from here).
  while (s.retained.size() > s.pending && (s.retained.size() > max_count || s.retained_bytes > max_bytes)) {
    s.retained_bytes -= item_bytes(s.retained.front().what);
    s.retained.pop_front();
    ++counters_.evicted;
  }
}

std::vector<FleetContributions> Outbox::pack(const std::string& body, std::deque<Numbered>::const_iterator begin,
                                             std::deque<Numbered>::const_iterator end, bool repair, int64_t now) const {
  std::vector<FleetContributions> out;
  const size_t overhead = message_overhead_bytes(self_, body);
  const size_t budget = static_cast<size_t>(std::max(options_.max_message_bytes, 1));
  size_t bytes = 0;
  for (auto it = begin; it != end; ++it) {
    const size_t b = item_bytes(it->what);
    if (out.empty() || out.back().contributions.size() >= kMaxItemsPerMessage || bytes + b > budget) {
      out.push_back(FleetContributions{now, self_, body, repair, it->seq, {}});
      bytes = overhead;
    }
    out.back().contributions.push_back(it->what);
    bytes += b;
  }
  return out;
}

std::vector<FleetContributions> Outbox::take_messages(int64_t now_utime) {
  std::vector<FleetContributions> out;
  for (auto& [body, s] : streams_) {
    if (s.pending == 0) continue;
    auto msgs =
        pack(body, s.retained.end() - static_cast<std::ptrdiff_t>(s.pending), s.retained.end(), false, now_utime);
    counters_.messages += static_cast<int64_t>(msgs.size());
    std::move(msgs.begin(), msgs.end(), std::back_inserter(out));
    s.pending = 0;
    evict(s);
  }
  return out;
}

std::vector<FleetControl> Outbox::heartbeat(int64_t now_utime) {
  if (streams_.empty()) return {};
  if (last_heartbeat_ && now_utime - *last_heartbeat_ < micros(options_.heartbeat_period_s)) return {};
  last_heartbeat_ = now_utime;
  std::vector<FleetControl> out;
  for (const auto& [body, s] : streams_) {
    if (out.empty() || out.back().streams.size() >= kMaxRangesPerMessage)
      out.push_back(FleetControl{now_utime, self_, FleetControl::Kind::kHeartbeat, "", {}});
    const int64_t sent = s.next_seq - 1 - static_cast<int64_t>(s.pending);
    const int64_t first = s.retained.empty() || s.retained.front().seq > sent ? 0 : s.retained.front().seq;
    out.back().streams.push_back(FleetRange{body, first, sent});
  }
  return out;
}

Outbox::Bucket& Outbox::bucket(const std::string& requester, int64_t now) {
  const double capacity = std::max(options_.repair_bytes_per_s, static_cast<double>(options_.max_message_bytes));
  auto [it, fresh] = buckets_.try_emplace(requester, Bucket{capacity, now});
  Bucket& b = it->second;
  if (!fresh && now > b.utime) {
    b.tokens = std::min(capacity, b.tokens + options_.repair_bytes_per_s * static_cast<double>(now - b.utime) * 1e-6);
    b.utime = now;
  }
  return b;
}

std::vector<FleetContributions> Outbox::answer(const FleetControl& request, int64_t now_utime) {
  if (request.kind != FleetControl::Kind::kRepair || request.daemon != self_) return {};
  if (request.sender == self_ || !members_.contains(request.sender)) {
    ++counters_.repair_refused;
    return {};
  }
  ++counters_.repair_requests;
  Bucket& b = bucket(request.sender, now_utime);
  std::vector<FleetContributions> out;
  for (const FleetRange& range : request.streams) answer_range(range, b, now_utime, out);
  return out;
}

void Outbox::answer_range(const FleetRange& range, Bucket& b, int64_t now, std::vector<FleetContributions>& out) {
  auto it = streams_.find(range.body);
  if (it == streams_.end()) {
    ++counters_.repair_refused;
    return;
  }
  const Stream& s = it->second;
  const int64_t sent = s.next_seq - 1 - static_cast<int64_t>(s.pending);  // what is queued goes anyway
  int64_t first = std::max<int64_t>(range.first, 1);
  const int64_t last = std::min({range.last, sent, first + std::max(options_.max_repair_range, 1) - 1});
  if (last < first) return;
  const int64_t oldest = s.retained.empty() ? s.next_seq : s.retained.front().seq;
  if (first < oldest) {
    counters_.repair_not_retained += std::min(last, oldest - 1) - first + 1;
    first = oldest;
  }
  if (last < first) return;
  const auto begin = s.retained.begin() + (first - oldest);
  const auto end = begin + (last - first + 1);
  auto stop = begin;
  for (; stop != end; ++stop) {
    const double bytes = static_cast<double>(item_bytes(stop->what));
    if (b.tokens < bytes) break;
    b.tokens -= bytes;
  }
  counters_.repair_limited += end - stop;
  counters_.repaired += stop - begin;
  auto msgs = pack(range.body, begin, stop, true, now);
  b.tokens -= static_cast<double>(msgs.size() * message_overhead_bytes(self_, range.body));
  counters_.repair_messages += static_cast<int64_t>(msgs.size());
  std::move(msgs.begin(), msgs.end(), std::back_inserter(out));
}

int64_t Outbox::next_seq(const std::string& body) const {
  auto it = streams_.find(body);
  return it == streams_.end() ? 1 : it->second.next_seq;
}

int64_t Outbox::first_retained(const std::string& body) const {
  auto it = streams_.find(body);
  return it == streams_.end() || it->second.retained.empty() ? 0 : it->second.retained.front().seq;
}

void Outbox::Stream::save(archive::ArchiveWriter& w) const { w(next_seq)(static_cast<uint64_t>(pending))(retained); }

void Outbox::Stream::load(archive::ArchiveReader& r) {
  uint64_t p = 0;
  r(next_seq)(p)(retained);
  pending = static_cast<size_t>(p);
  if (pending > retained.size()) r.fail("an outbox stream with more queued contributions than it holds");
  for (size_t i = 0; i < retained.size(); ++i)
    if (retained[i].seq != next_seq - static_cast<int64_t>(retained.size() - i))
      r.fail("an outbox stream whose retained contributions are not numbered up to its next number");
  retained_bytes = 0;
  for (const Numbered& n : retained) retained_bytes += item_bytes(n.what);
}

void Outbox::save(archive::ArchiveWriter& w) const {
  w(streams_)(last_heartbeat_);
  outbox_counter_fields(w, counters_);
}

void Outbox::load(archive::ArchiveReader& r) {
  r(streams_)(last_heartbeat_);
  outbox_counter_fields(r, counters_);
  last_heartbeat_.reset();  // the clock of the saved run: the first heartbeat goes at once
}

// ---- Inbox -----------------------------------------------------------------------------------------------------

Inbox::Inbox(std::string self, FleetExchangeOptions options)
    : self_(std::move(self)),
      options_(std::move(options)),
      members_(options_.members.begin(), options_.members.end()) {}

bool Inbox::own(const std::string& body) {
  if (local_.contains(body)) return true;
  if (streams_.contains(body)) {
    ++counters_.claimed;
    return false;
  }
  local_.insert(body);
  return true;
}

Inbox::Stream* Inbox::stream_for(const std::string& sender, const std::string& body) {
  if (sender == self_) {
    ++counters_.own;
    return nullptr;
  }
  if (!members_.contains(sender)) {
    ++counters_.not_member;
    return nullptr;
  }
  if (local_.contains(body)) {
    ++counters_.local_body;
    return nullptr;
  }
  if (auto it = streams_.find(body); it != streams_.end()) {
    if (it->second.owner == sender) return &it->second;
    ++counters_.claimed;
    return nullptr;
  }
  int& count = streams_of_[sender];  // members only: bounded
  if (count >= options_.max_streams_per_sender) {
    ++counters_.too_many_streams;
    return nullptr;
  }
  ++count;
  Stream& s = streams_[body];
  s.owner = sender;
  s.backoff_s = options_.repair_backoff_s;
  return &s;
}

void Inbox::hold(Stream& s, int64_t seq, What what) {
  if (seq < s.next || s.held.contains(seq)) {
    ++counters_.duplicates;
    return;
  }
  const size_t bytes = item_bytes(what);
  if (seq - s.next >= options_.reorder_window ||
      (seq != s.next && s.held_bytes + bytes > static_cast<size_t>(std::max(options_.reorder_mb, 0)) * kMegabyte)) {
    ++counters_.out_of_window;
    return;
  }
  s.held_bytes += bytes;
  s.known_last = std::max(s.known_last, seq);
  s.held.emplace(seq, std::move(what));
}

void Inbox::deliver(const std::string& body, Stream& s, int64_t now, std::vector<slam::GraphContribution>& out) {
  const int64_t before = s.next;
  for (;;) {
    auto it = s.held.begin();
    if (it != s.held.end() && it->first == s.next) {
      s.held_bytes -= item_bytes(it->second);
      out.push_back(slam::GraphContribution{body, std::move(it->second)});
      s.held.erase(it);
      ++s.next;
      ++counters_.delivered;
    } else if (s.next < s.owner_first) {
      // The owner no longer has what is missing here: skip it, up to what is held or what the owner still has.
      const int64_t to = it == s.held.end() ? s.owner_first : std::min(s.owner_first, it->first);
      counters_.lost += to - s.next;
      s.next = to;
    } else {
      break;
    }
  }
  schedule(s, now, s.next != before);
}

void Inbox::schedule(Stream& s, int64_t now, bool moved) {
  if (s.known_last < s.next) {  // nothing known beyond what was delivered: no gap
    s.ask_at = 0;
    s.backoff_s = options_.repair_backoff_s;
    return;
  }
  if (moved || s.ask_at == 0) {
    s.backoff_s = options_.repair_backoff_s;
    s.ask_at = now + std::max<int64_t>(micros(s.backoff_s), 1);
  }
}

void Inbox::heard(Stream& s, int64_t now) {
  if (s.ask_at != 0 && s.heard_at != 0 && now - s.heard_at > micros(s.backoff_s)) {
    s.backoff_s = options_.repair_backoff_s;
    s.ask_at = std::min(s.ask_at, now + std::max<int64_t>(micros(s.backoff_s), 1));
  }
  s.heard_at = now;
}

std::vector<slam::GraphContribution> Inbox::receive(const FleetContributions& m, int64_t now_utime) {
  Stream* s = stream_for(m.sender, m.body);
  if (s == nullptr) return {};
  heard(*s, now_utime);
  ++counters_.messages;
  if (!m.repair) s->sent_utime = std::max(s->sent_utime, m.utime);
  const auto n = static_cast<int64_t>(m.contributions.size());
  if (m.first < 1 || m.first > kMaxSeq - n) {
    counters_.out_of_window += n;
    return {};
  }
  for (int64_t i = 0; i < n; ++i) hold(*s, m.first + i, m.contributions[static_cast<size_t>(i)]);
  std::vector<slam::GraphContribution> out;
  deliver(m.body, *s, now_utime, out);
  return out;
}

std::vector<slam::GraphContribution> Inbox::receive(const FleetControl& m, int64_t now_utime) {
  if (m.kind != FleetControl::Kind::kHeartbeat) return {};
  if (m.sender == self_) {
    ++counters_.own;
    return {};
  }
  if (!members_.contains(m.sender)) {
    ++counters_.not_member;
    return {};
  }
  ++counters_.heartbeats;
  std::vector<slam::GraphContribution> out;
  for (const FleetRange& range : m.streams) {
    if (range.last < 1 || range.last > kMaxSeq || range.first < 0 || range.first > range.last) continue;
    Stream* s = stream_for(m.sender, range.body);
    if (s == nullptr) continue;
    heard(*s, now_utime);
    if (m.utime > s->sent_utime) {
      if (range.last < std::max(s->beat_last, s->next - 1)) ++counters_.owner_rewound;
      s->sent_utime = m.utime;
    }
    s->beat_last = range.last;
    s->known_last = std::max(s->known_last, range.last);
    s->owner_first = range.first;
    deliver(range.body, *s, now_utime, out);
  }
  return out;
}

std::vector<FleetRange> Inbox::holes(const std::string& body, const Stream& s) const {
  constexpr size_t kMaxHolesPerStream = 8;
  std::vector<FleetRange> out;
  int64_t budget = std::max(options_.max_repair_range, 1);
  int64_t at = s.next;
  auto it = s.held.begin();
  while (at <= s.known_last && budget > 0 && out.size() < kMaxHolesPerStream) {
    const int64_t end = it != s.held.end() ? it->first - 1 : s.known_last;
    if (end >= at) {
      const int64_t last = std::min(end, at + budget - 1);
      out.push_back(FleetRange{body, at, last});
      budget -= last - at + 1;
    }
    if (it == s.held.end()) break;
    at = it->first + 1;  // past the run held from here
    for (++it; it != s.held.end() && it->first == at; ++it) ++at;
  }
  return out;
}

std::vector<FleetControl> Inbox::repair_requests(int64_t now_utime) {
  std::map<std::string, FleetControl> by_owner;
  for (auto& [body, s] : streams_) {
    if (s.ask_at == 0 || now_utime < s.ask_at) continue;
    FleetControl& request =
        by_owner.try_emplace(s.owner, FleetControl{now_utime, self_, FleetControl::Kind::kRepair, s.owner, {}})
            .first->second;
    for (FleetRange& r : holes(body, s)) {
      if (request.streams.size() >= kMaxRangesPerMessage) break;  // the rest at this stream's next turn
      counters_.repair_asked += r.last - r.first + 1;
      request.streams.push_back(std::move(r));
    }
    s.backoff_s = std::min(2 * s.backoff_s, options_.repair_backoff_max_s);
    s.ask_at = now_utime + std::max<int64_t>(micros(s.backoff_s), 1);
  }
  std::vector<FleetControl> out;
  for (auto& [owner, request] : by_owner)
    if (!request.streams.empty()) out.push_back(std::move(request));
  counters_.repair_requests += static_cast<int64_t>(out.size());
  return out;
}

int64_t Inbox::next_expected(const std::string& body) const {
  auto it = streams_.find(body);
  return it == streams_.end() ? 1 : it->second.next;
}

std::string Inbox::owner(const std::string& body) const {
  auto it = streams_.find(body);
  return it == streams_.end() ? std::string() : it->second.owner;
}

size_t Inbox::held() const {
  size_t n = 0;
  for (const auto& [body, s] : streams_) n += s.held.size();
  return n;
}

void Inbox::Stream::save(archive::ArchiveWriter& w) const {
  w(owner)(next)(known_last)(owner_first)(static_cast<uint64_t>(held.size()));
  for (const auto& [seq, what] : held) w(seq)(what);
}

void Inbox::Stream::load(archive::ArchiveReader& r) {
  r(owner)(next)(known_last)(owner_first);
  const uint64_t n = r.count(12, "an inbox stream's held contributions");
  held.clear();
  held_bytes = 0;
  for (uint64_t i = 0; i < n; ++i) {
    int64_t seq = 0;
    What what;
    r(seq)(what);
    if (seq <= next || !held.emplace(seq, std::move(what)).second)
      r.fail("an inbox stream holding a contribution at or before its next number, or twice");
  }
  for (const auto& [seq, what] : held) held_bytes += item_bytes(what);
  ask_at = 0;
}

void Inbox::save(archive::ArchiveWriter& w) const {
  w(streams_)(std::vector<std::string>(local_.begin(), local_.end()));
  inbox_counter_fields(w, counters_);
}

void Inbox::load(archive::ArchiveReader& r) {
  std::vector<std::string> local;
  r(streams_)(local);
  inbox_counter_fields(r, counters_);
  local_ = std::set<std::string>(local.begin(), local.end());
  streams_of_.clear();
  for (auto& [body, s] : streams_) {
    ++streams_of_[s.owner];
    s.backoff_s = options_.repair_backoff_s;
    // A gap saved is asked for at the restarted daemon's first call for repair requests (the saved run's clock is
    // not this one's).
    if (s.known_last >= s.next) s.ask_at = 1;
  }
}

std::vector<std::pair<std::string, int64_t>> FleetExchange::counters() const {
  const OutboxCounters& o = outbox.counters();
  const InboxCounters& i = inbox.counters();
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
          {"fleet_in_streams", static_cast<int64_t>(inbox.streams())},
          {"fleet_in_held", static_cast<int64_t>(inbox.held())}};
}

FleetExchange::Due FleetExchange::due(int64_t now_utime) {
  Due d;
  d.contributions = outbox.take_messages(now_utime);
  d.control = outbox.heartbeat(now_utime);
  for (FleetControl& r : inbox.repair_requests(now_utime)) d.control.push_back(std::move(r));
  return d;
}

}  // namespace sextant::engine::fleet
