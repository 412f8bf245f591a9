// The exchange's sending side, Outbox (fleet_exchange.hpp).
#include "daemon/engine/fleet_exchange.hpp"
#include "daemon/engine/fleet_exchange_detail.hpp"

#include <algorithm>

namespace sextant::engine::fleet {
namespace {

using namespace slam;
using detail::kMegabyte;
using detail::micros;

template <class A, class C>
void outbox_counter_fields(A& a, C& c) {
  a(c.contributions)(c.messages)(c.evicted)(c.repair_requests)(c.repair_refused)(c.repaired)(c.repair_messages)(
      c.repair_limited)(c.repair_not_retained);
}

}  // namespace

Outbox::Outbox(std::string self, FleetExchangeOptions options)
    : self_(std::move(self)),
      options_(std::move(options)),
      members_(options_.members.begin(), options_.members.end()) {}

void Retained::push(Numbered n) {
  bytes += item_bytes(n.what);
  items.push_back(std::move(n));
}

int64_t Retained::evict(const FleetExchangeOptions& o, size_t keep) {
  const size_t max_count = static_cast<size_t>(std::max(o.retain, 0));
  const size_t max_bytes = static_cast<size_t>(std::max(o.retain_mb, 0)) * kMegabyte;
  int64_t gone = 0;
  while (items.size() > keep && (items.size() > max_count || bytes > max_bytes)) {
    bytes -= item_bytes(items.front().what);
    items.pop_front();
    ++gone;
  }
  return gone;
}

void Outbox::add(const slam::GraphContribution& c) {
  Stream& s = streams_[c.body];
  for (What& what : split_for_wire(c.what)) {
    if (wire_check_ && !wire_check_(what).empty()) {
      what = kNothing;
      ++counters_.refused;
    }
    s.retained.push(Numbered{s.next_seq++, std::move(what)});
    ++s.pending;
    ++counters_.contributions;
  }
  evict(s);
}

bool Outbox::adopt(const std::string& body, const Numbered& n) {
  auto it = streams_.find(body);
  if (it == streams_.end() || n.seq != it->second.next_seq) return false;
  Stream& s = it->second;
  s.retained.push(n);
  ++s.next_seq;
  // Newer than what is still queued: it goes with it (a duplicate to the others, dropped there).
  if (s.pending > 0) ++s.pending;
  evict(s);
  return true;
}

// What is not sent yet stays (it goes with the next take_messages, then may go from here).
void Outbox::evict(Stream& s) { counters_.evicted += s.retained.evict(options_, s.pending); }

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
    auto msgs = pack(body, s.retained.items.end() - static_cast<std::ptrdiff_t>(s.pending), s.retained.items.end(),
                     false, now_utime);
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
    const int64_t first = s.retained.items.empty() || s.retained.first() > sent ? 0 : s.retained.first();
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
  for (const FleetRange& range : request.streams) {
    auto it = streams_.find(range.body);
    if (it == streams_.end()) {
      ++counters_.repair_refused;
      continue;
    }
    const Stream& s = it->second;
    answer_range(range, s.retained, s.next_seq - 1 - static_cast<int64_t>(s.pending), b, now_utime, out,
                 counters_.repaired);
  }
  return out;
}

std::vector<FleetContributions> Outbox::answer_tail(const FleetControl& request, const Inbox& copies,
                                                    int64_t now_utime) {
  if (request.kind != FleetControl::Kind::kRepair || request.daemon != request.sender || request.sender == self_)
    return {};
  if (!members_.contains(request.sender)) {
    ++counters_.repair_refused;
    return {};
  }
  ++counters_.tail_requests;
  Bucket& b = bucket(request.sender, now_utime);
  std::vector<FleetContributions> out;
  for (const FleetRange& range : request.streams) {
    if (const Retained* copy = copies.copy_of(range.body, request.sender))
      answer_range(range, *copy, copy->last(), b, now_utime, out, counters_.repaired);
    // What is held ahead of a gap, run by run: the owner may have lost the gap too, and then numbers its next
    // contributions after these (TailFetch), as this daemon will apply them.
    const std::map<int64_t, What>* held = copies.held_of(range.body, request.sender);
    Retained run;
    for (auto it = held ? held->lower_bound(range.first) : std::map<int64_t, What>::const_iterator{};
         held && it != held->end(); ++it) {
      run.push(Numbered{it->first, it->second});
      const auto next = std::next(it);
      if (next != held->end() && next->first == it->first + 1) continue;
      answer_range(FleetRange{range.body, run.first(), range.last}, run, run.last(), b, now_utime, out,
                   counters_.repaired);
      run.clear();
    }
  }
  return out;
}

std::vector<FleetContributions> Outbox::relay(const FleetControl& request, const Inbox& copies, int64_t now_utime) {
  if (request.kind != FleetControl::Kind::kRepair || request.sender == self_ || request.daemon == self_ ||
      request.daemon == request.sender || !members_.contains(request.sender))
    return {};
  // The bodies whose first range asks, for the kRelayAfterAsks-th time in a row or more, for the same number, with
  // this daemon's copy of their stream.
  std::map<std::string, const Retained*> stuck;
  std::set<std::string> counted;
  for (const FleetRange& range : request.streams) {
    const Retained* copy = copies.copy_of(range.body, request.daemon);
    if (!counted.insert(range.body).second || copy == nullptr) continue;
    auto& [first, times] = overheard_asks_[{request.sender, range.body}];
    times = first == range.first ? times + 1 : 1;
    first = range.first;
    if (times >= kRelayAfterAsks) stuck.emplace(range.body, copy);
  }
  if (stuck.empty()) return {};
  Bucket& b = bucket(request.sender, now_utime);
  std::vector<FleetContributions> out;
  for (const FleetRange& range : request.streams) {
    const auto it = stuck.find(range.body);
    if (it == stuck.end()) continue;
    const Retained& copy = *it->second;
    if (copy.items.empty() || range.last < copy.first()) continue;  // not held here: not this daemon's to count
    const FleetRange held{range.body, std::max(range.first, copy.first()), range.last};
    answer_range(held, copy, copy.last(), b, now_utime, out, counters_.relayed);
  }
  return out;
}

void Outbox::answer_range(const FleetRange& range, const Retained& log, int64_t last_held, Bucket& b, int64_t now,
                          std::vector<FleetContributions>& out, int64_t& sent) {
  int64_t first = std::max<int64_t>(range.first, 1);
  const int64_t last = std::min({range.last, last_held, first + std::max(options_.max_repair_range, 1) - 1});
  if (last < first) return;
  const int64_t oldest = log.items.empty() ? last_held + 1 : log.first();
  if (first < oldest) {
    counters_.repair_not_retained += std::min(last, oldest - 1) - first + 1;
    first = oldest;
  }
  if (last < first) return;
  const auto begin = log.items.begin() + (first - oldest);
  const auto end = begin + (last - first + 1);
  auto stop = begin;
  for (; stop != end; ++stop) {
    const double bytes = static_cast<double>(item_bytes(stop->what));
    if (b.tokens < bytes) break;
    b.tokens -= bytes;
  }
  counters_.repair_limited += end - stop;
  sent += stop - begin;
  auto msgs = pack(range.body, begin, stop, true, now);
  b.tokens -= static_cast<double>(msgs.size() * message_overhead_bytes(self_, range.body));
  counters_.repair_messages += static_cast<int64_t>(msgs.size());
  std::move(msgs.begin(), msgs.end(), std::back_inserter(out));
}

int64_t Outbox::next_seq(const std::string& body) const {
  auto it = streams_.find(body);
  return it == streams_.end() ? 1 : it->second.next_seq;
}

std::vector<std::string> Outbox::bodies() const {
  std::vector<std::string> out;
  for (const auto& [body, s] : streams_) out.push_back(body);
  return out;
}

int64_t Outbox::first_retained(const std::string& body) const {
  auto it = streams_.find(body);
  return it == streams_.end() ? 0 : it->second.retained.first();
}

void Outbox::Stream::save(archive::ArchiveWriter& w) const {
  w(next_seq)(static_cast<uint64_t>(pending))(retained.items);
}

void Outbox::Stream::load(archive::ArchiveReader& r) {
  uint64_t p = 0;
  std::deque<Numbered> items;
  r(next_seq)(p)(items);
  pending = static_cast<size_t>(p);
  if (pending > items.size()) r.fail("an outbox stream with more queued contributions than it holds");
  for (size_t i = 0; i < items.size(); ++i)
    if (items[i].seq != next_seq - static_cast<int64_t>(items.size() - i))
      r.fail("an outbox stream whose retained contributions are not numbered up to its next number");
  retained.clear();
  for (Numbered& n : items) retained.push(std::move(n));
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

}  // namespace sextant::engine::fleet
