// A restarted owner fetching its own streams' tails back from the fleet, TailFetch (fleet_exchange.hpp).
#include "daemon/engine/fleet_exchange.hpp"
#include "daemon/engine/fleet_exchange_detail.hpp"

#include <algorithm>

namespace sextant::engine::fleet {

using detail::kMaxSeq;
using detail::micros;

TailFetch::TailFetch(std::string self, FleetExchangeOptions options)
    : self_(std::move(self)),
      options_(std::move(options)),
      members_(options_.members.begin(), options_.members.end()) {}

void TailFetch::start(const Outbox& outbox) {
  const std::vector<std::string> bodies = outbox.bodies();
  bodies_ = std::set<std::string>(bodies.begin(), bodies.end());
  const bool others = std::any_of(members_.begin(), members_.end(), [&](const auto& m) { return m != self_; });
  waiting_ = others && !bodies_.empty();
  stop_ = false;
  ahead_.clear();
  quiet_until_ = 0;
  ask_at_ = 0;
  backoff_s_ = options_.repair_backoff_s;
}

std::vector<Numbered> TailFetch::receive(const FleetContributions& m, const Outbox& outbox, int64_t now_utime) {
  if (!waiting_ || m.sender == self_) return {};  // this daemon's own repairs, brought back by multicast
  const auto n = static_cast<int64_t>(m.contributions.size());
  if (!members_.contains(m.sender) || !bodies_.contains(m.body) || m.first < 1 || m.first > kMaxSeq - n) {
    ++counters_.refused;
    return {};
  }
  int64_t next = outbox.next_seq(m.body);
  std::map<int64_t, What>& ahead = ahead_[m.body];
  std::vector<Numbered> out;
  for (int64_t i = 0; i < n; ++i) {
    const int64_t seq = m.first + i;
    const What& what = m.contributions[static_cast<size_t>(i)];
    if (seq < next || ahead.contains(seq)) {
      ++counters_.duplicates;
    } else if (seq == next) {
      out.push_back(Numbered{next++, what});
    } else if (seq - next < options_.reorder_window) {
      ahead.emplace(seq, what);  // the next request asks from `next` again
    } else {
      ++counters_.out_of_order;
    }
  }
  for (auto it = ahead.begin(); it != ahead.end() && it->first <= next; it = ahead.erase(it))
    if (it->first == next) out.push_back(Numbered{next++, std::move(it->second)});
  if (!out.empty()) {  // more may follow: the wait goes on, and the rest is asked for soon
    counters_.adopted += static_cast<int64_t>(out.size());
    quiet_until_ = now_utime + std::max<int64_t>(micros(options_.restart_wait_s), 1);
    backoff_s_ = options_.repair_backoff_s;
    ask_at_ = now_utime + std::max<int64_t>(micros(backoff_s_), 1);
  }
  return out;
}

std::vector<std::pair<std::string, Numbered>> TailFetch::fill_holes(const Outbox& outbox) {
  std::vector<std::pair<std::string, Numbered>> out;
  for (auto& [body, ahead] : ahead_) {
    int64_t next = outbox.next_seq(body);
    for (auto& [seq, what] : ahead) {
      if (seq < next) continue;
      counters_.lost += seq - next;
      for (; next < seq; ++next) out.emplace_back(body, Numbered{next, kNothing});
      out.emplace_back(body, Numbered{next++, std::move(what)});
    }
  }
  ahead_.clear();
  return out;
}

std::vector<FleetControl> TailFetch::requests(const Outbox& outbox, int64_t now_utime,
                                              std::vector<std::pair<std::string, Numbered>>& ended) {
  if (!waiting_) return {};
  if (quiet_until_ == 0) {  // the first call after the restart: this run's clock
    quiet_until_ = now_utime + std::max<int64_t>(micros(options_.restart_wait_s), 1);
    ask_at_ = now_utime;
  }
  if (stop_ || now_utime >= quiet_until_) {
    waiting_ = false;
    ended = fill_holes(outbox);
    return {};
  }
  if (now_utime < ask_at_) return {};
  std::vector<FleetControl> out;
  const int64_t span = std::max(options_.max_repair_range, 1);
  for (const std::string& body : bodies_) {
    if (out.empty() || out.back().streams.size() >= kMaxRangesPerMessage)
      out.push_back(FleetControl{now_utime, self_, FleetControl::Kind::kRepair, self_, {}});
    const int64_t next = outbox.next_seq(body);
    out.back().streams.push_back(FleetRange{body, next, std::min(next + span - 1, kMaxSeq)});
  }
  counters_.requests += static_cast<int64_t>(out.size());
  ask_at_ = now_utime + std::max<int64_t>(micros(backoff_s_), 1);
  backoff_s_ = std::min(2 * backoff_s_, options_.repair_backoff_max_s);
  return out;
}

}  // namespace sextant::engine::fleet
