#pragma once
// Late measurements for a recursive filter: a bounded history of its inputs, kept in time order, and checkpoints of
// its state, so that an input arriving after newer ones is inserted where it belongs and every input after it is
// re-applied in order (robot_localization's `smooth_lagged_data` + `history_length`; fuse's fixed lag).
//
//  - Inputs are ordered by the key (utime, rank, arrival): `rank` orders inputs of equal utime by kind (e.g.
//    odometry 0 before sightings 1), arrival order breaks the remaining ties.  Processing a set of inputs that
//    arrive in any order therefore gives exactly the state that processing them in key order gives (bit for bit:
//    the same operations run on the same numbers).
//  - An input with utime < newest - window is too late: it is refused (the caller counts and drops it).
//  - Checkpoints (copies of the state) are taken every `checkpoint_interval` of measurement time; a late input
//    restores the newest checkpoint before it and re-applies from there.  The history keeps only what a late input
//    inside the window can need: the newest checkpoint older than the window start and the inputs after it.
//    Memory: about window / interval + 2 states and window's worth of inputs; re-application of a late input costs
//    the inputs between the checkpoint and now (at most window + interval of them).
// `State` must be copyable; `apply(State&, const Input&)` must be deterministic and must not have effects outside
// the state (counters belong in the state, so that re-application does not count twice).
#include "estimators/archive/binary_archive.hpp"

#include <algorithm>
#include <cstdint>
#include <deque>
#include <limits>
#include <stdexcept>
#include <tuple>
#include <utility>

namespace sextant::filter {

template <class State, class Input>
class MeasurementHistory {
 public:
  enum class Outcome {
    applied,    // newest input: applied to the current state
    reapplied,  // late input inside the window: inserted, the inputs after it re-applied
    too_late,   // older than the window: refused, the state is unchanged
  };

  /// `window_us` >= 0: how far behind the newest input a late one is still accepted.  `initial`: the state before
  /// any input.
  MeasurementHistory(int64_t window_us, State initial)
      : window_(window_us), interval_(std::max<int64_t>(window_us / 8, kMinInterval)), state_(std::move(initial)) {
    if (window_us < 0) throw std::invalid_argument("MeasurementHistory: negative window");
    checkpoints_.push_back({kBeforeAll, state_});
  }

  /// Adds `input` stamped `utime`; `apply` updates a state with one input.
  template <class Apply>
  Outcome add(int64_t utime, int rank, Input input, Apply&& apply) {
    if (!inputs_.empty() && utime < newest_ - window_) return Outcome::too_late;
    const Key key{utime, rank, arrivals_++};
    newest_ = inputs_.empty() ? utime : std::max(newest_, utime);
    if (inputs_.empty() || inputs_.back().key < key) {
      if (!inputs_.empty()) checkpoint_if_due(inputs_.back().key);
      apply(state_, input);
      inputs_.push_back({key, std::move(input)});
      prune();
      return Outcome::applied;
    }
    // Late: back to the newest checkpoint before `key`, then every input after it in key order.
    while (checkpoints_.size() > 1 && !(checkpoints_.back().last < key)) checkpoints_.pop_back();
    state_ = checkpoints_.back().state;
    const Key from = checkpoints_.back().last;
    const auto at =
        std::upper_bound(inputs_.begin(), inputs_.end(), key, [](const Key& k, const Entry& e) { return k < e.key; });
    inputs_.insert(at, Entry{key, std::move(input)});
    auto it =
        std::upper_bound(inputs_.begin(), inputs_.end(), from, [](const Key& k, const Entry& e) { return k < e.key; });
    for (Key last = from; it != inputs_.end(); last = it->key, ++it) {
      if (!(last.utime == kBeforeAll.utime)) checkpoint_if_due(last);
      apply(state_, it->input);
    }
    prune();
    return Outcome::reapplied;
  }

  const State& state() const { return state_; }
  State& state() { return state_; }
  /// The newest utime added (0 before any input).
  int64_t newest() const { return newest_; }
  size_t inputs() const { return inputs_.size(); }
  size_t checkpoints() const { return checkpoints_.size(); }

  /// The whole history in the binary archive: the state, the inputs of the window with their keys and the
  /// checkpoints, so that a restored history re-applies a late input exactly as this one would.  State and Input
  /// must be archivable (binary_archive.hpp); the window is the constructor's.  `fresh` is a state as the caller
  /// constructs it before any input (its configured parts): each restored state is loaded into a copy of it.
  void save(archive::ArchiveWriter& w) const {
    w(state_)(newest_)(arrivals_);
    w(static_cast<uint64_t>(inputs_.size()));
    for (const Entry& e : inputs_) w(e.key.utime)(e.key.rank)(e.key.arrival)(e.input);
    w(static_cast<uint64_t>(checkpoints_.size()));
    for (const Checkpoint& c : checkpoints_) w(c.last.utime)(c.last.rank)(c.last.arrival)(c.state);
  }
  void load(archive::ArchiveReader& r, const State& fresh) {
    state_ = fresh;
    r(state_)(newest_)(arrivals_);
    inputs_.clear();
    const uint64_t n = r.count(1, "the history's inputs");
    for (uint64_t i = 0; i < n; ++i) {
      Entry e{kBeforeAll, Input{}};
      r(e.key.utime)(e.key.rank)(e.key.arrival)(e.input);
      if (!inputs_.empty() && !(inputs_.back().key < e.key)) r.fail("a history whose inputs are not in order");
      inputs_.push_back(std::move(e));
    }
    checkpoints_.clear();
    const uint64_t c = r.count(1, "the history's checkpoints");
    if (c == 0) r.fail("a history without its first checkpoint");
    for (uint64_t i = 0; i < c; ++i) {
      Checkpoint k{kBeforeAll, fresh};
      r(k.last.utime)(k.last.rank)(k.last.arrival)(k.state);
      checkpoints_.push_back(std::move(k));
    }
  }

 private:
  struct Key {
    int64_t utime;
    int rank;
    uint64_t arrival;
    bool operator<(const Key& o) const { return std::tie(utime, rank, arrival) < std::tie(o.utime, o.rank, o.arrival); }
  };
  struct Entry {
    Key key;
    Input input;
  };
  struct Checkpoint {
    Key last;  // the state after applying every input with a key <= last
    State state;
  };
  static constexpr Key kBeforeAll{std::numeric_limits<int64_t>::min(), 0, 0};
  static constexpr int64_t kMinInterval = 10'000;  // µs: no checkpoint more often than every 10 ms

  // Before applying the next input, with every input up to `last` applied: checkpoint the current state when the
  // newest checkpoint is old enough.
  void checkpoint_if_due(const Key& last) {
    const Key& previous = checkpoints_.back().last;
    if (!(previous < last)) return;
    if (previous.utime == kBeforeAll.utime || last.utime - previous.utime >= interval_)
      checkpoints_.push_back({last, state_});
  }

  // Keep the newest checkpoint older than the window start and the inputs after it.
  void prune() {
    const int64_t start = newest_ - window_;
    while (checkpoints_.size() > 1 && checkpoints_[1].last.utime < start) checkpoints_.pop_front();
    const Key& first = checkpoints_.front().last;
    while (!inputs_.empty() && !(first < inputs_.front().key)) inputs_.pop_front();
  }

  int64_t window_, interval_;
  State state_;
  std::deque<Entry> inputs_;
  std::deque<Checkpoint> checkpoints_;
  int64_t newest_ = 0;
  uint64_t arrivals_ = 0;
};

}  // namespace sextant::filter
