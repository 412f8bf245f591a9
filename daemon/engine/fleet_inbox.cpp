// The exchange's receiving side, Inbox (fleet_exchange.hpp).
#include "daemon/engine/fleet_exchange.hpp"
#include "daemon/engine/fleet_exchange_detail.hpp"

#include <algorithm>

namespace sextant::engine::fleet {
namespace {

using namespace slam;
using detail::kMaxSeq;
using detail::kMegabyte;
using detail::micros;

template <class A, class C>
void inbox_counter_fields(A& a, C& c) {
  a(c.messages)(c.delivered)(c.duplicates)(c.out_of_window)(c.own)(c.not_member)(c.local_body)(c.claimed)(
      c.too_many_streams)(c.lost)(c.repair_requests)(c.repair_asked)(c.heartbeats)(c.owner_rewound);
}

}  // namespace

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

bool Inbox::hold(Stream& s, int64_t seq, What what) {
  if (seq < s.next || s.held.contains(seq)) {
    ++counters_.duplicates;
    return false;
  }
  const size_t bytes = item_bytes(what);
  if (seq - s.next >= options_.reorder_window ||
      (seq != s.next && s.held_bytes + bytes > static_cast<size_t>(std::max(options_.reorder_mb, 0)) * kMegabyte)) {
    ++counters_.out_of_window;
    return false;
  }
  const bool hole = seq <= s.known_last;
  s.held_bytes += bytes;
  s.known_last = std::max(s.known_last, seq);
  s.held.emplace(seq, std::move(what));
  return hole;
}

void Inbox::deliver(const std::string& body, Stream& s, int64_t now, std::vector<slam::GraphContribution>& out) {
  const int64_t before = s.next;
  for (;;) {
    auto it = s.held.begin();
    if (it != s.held.end() && it->first == s.next) {
      s.held_bytes -= item_bytes(it->second);
      s.copy.push(Numbered{s.next, it->second});
      s.copy.evict(options_, 0);
      out.push_back(slam::GraphContribution{body, std::move(it->second)});
      s.held.erase(it);
      ++s.next;
      ++counters_.delivered;
    } else if (s.next < s.owner_first) {
      // The owner no longer has what is missing here: skip it, up to what is held or what the owner still has.
      const int64_t to = it == s.held.end() ? s.owner_first : std::min(s.owner_first, it->first);
      counters_.lost += to - s.next;
      s.next = to;
      s.copy.clear();  // the copy holds a run without a gap
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
    s.asks = 0;
    return;
  }
  if (moved || s.ask_at == 0) {
    s.backoff_s = options_.repair_backoff_s;
    s.ask_at = now + std::max<int64_t>(micros(s.backoff_s), 1);
  }
}

void Inbox::ask_again_soon(Stream& s, int64_t now) {
  if (s.ask_at == 0) return;  // no gap
  s.backoff_s = options_.repair_backoff_s;
  s.ask_at = std::min(s.ask_at, now + std::max<int64_t>(micros(s.backoff_s), 1));
}

void Inbox::heard(Stream& s, int64_t now) {
  if (s.heard_at != 0 && now - s.heard_at > micros(s.backoff_s)) ask_again_soon(s, now);
  s.heard_at = now;
}

bool Inbox::overheard(const FleetContributions& m) {
  if (!m.repair || m.sender == self_ || !members_.contains(m.sender)) return false;
  // A repair answers a request for a stream its requester knows from the owner: one that is not known here from its
  // sender (another member's answer to a restarted owner, or a repair of a stream this daemon has not heard of yet)
  // opens no stream and changes none.
  const auto it = streams_.find(m.body);
  if (local_.contains(m.body) || it == streams_.end() || it->second.owner != m.sender) {
    ++counters_.repairs_overheard;
    return true;
  }
  return false;
}

Inbox::Stream* Inbox::relayed_stream(const FleetContributions& m) {
  if (!m.repair || m.sender == self_ || !members_.contains(m.sender) || local_.contains(m.body)) return nullptr;
  const auto it = streams_.find(m.body);
  if (it == streams_.end() || it->second.owner == m.sender || it->second.asks < kRelayAfterAsks) return nullptr;
  return &it->second;
}

std::vector<slam::GraphContribution> Inbox::receive(const FleetContributions& m, int64_t now_utime) {
  if (Stream* s = relayed_stream(m)) {  // not the owner speaking: its silence is not ended by it
    ++counters_.relays;
    return take(m, *s, now_utime);
  }
  if (overheard(m)) return {};
  Stream* s = stream_for(m.sender, m.body);
  if (s == nullptr) return {};
  heard(*s, now_utime);
  ++counters_.messages;
  if (!m.repair) s->sent_utime = std::max(s->sent_utime, m.utime);
  return take(m, *s, now_utime);
}

std::vector<slam::GraphContribution> Inbox::take(const FleetContributions& m, Stream& s, int64_t now) {
  const auto n = static_cast<int64_t>(m.contributions.size());
  if (m.first < 1 || m.first > kMaxSeq - n) {
    counters_.out_of_window += n;
    return {};
  }
  bool filled = false;
  for (int64_t i = 0; i < n; ++i) filled = hold(s, m.first + i, m.contributions[static_cast<size_t>(i)]) || filled;
  std::vector<slam::GraphContribution> out;
  deliver(m.body, s, now, out);
  if (m.repair && filled) ask_again_soon(s, now);
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
    std::vector<FleetRange> asked = holes(body, s);
    if (!asked.empty() && request.streams.size() < kMaxRangesPerMessage) {  // the requests in a row for one number
      s.asks = asked.front().first == s.asked_first ? s.asks + 1 : 1;
      s.asked_first = asked.front().first;
    }
    for (FleetRange& r : asked) {
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

const Retained* Inbox::copy_of(const std::string& body, const std::string& owner) const {
  const auto it = streams_.find(body);
  return it == streams_.end() || it->second.owner != owner ? nullptr : &it->second.copy;
}

const std::map<int64_t, What>* Inbox::held_of(const std::string& body, const std::string& owner) const {
  const auto it = streams_.find(body);
  return it == streams_.end() || it->second.owner != owner ? nullptr : &it->second.held;
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

}  // namespace sextant::engine::fleet
