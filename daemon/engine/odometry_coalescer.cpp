#include "daemon/engine/odometry_coalescer.hpp"

#include "daemon/engine/pose_conversion.hpp"
#include "daemon/engine/pose_covariance.hpp"

#include <algorithm>

namespace sextant::engine {
namespace {

constexpr size_t kMaxWaitingTimes = 4096;  // per body; beyond, a waiting event is taken up over a merged interval

// The floor increment_covariance() adds to the variances a source uses, to take it off a composed covariance again.
Matrix6 variance_floor(bool planar, double min_variance) {
  Matrix6 f = Matrix6::Zero();
  if (planar) {
    for (int i : {0, 1, 5}) f(i, i) = min_variance;
  } else {
    f.diagonal().setConstant(min_variance);
  }
  return f;
}

// The body an event is about (empty for events of no body, e.g. bearing scans).
std::string source_of(const Event& e) {
  return std::visit([](const auto& x) -> std::string {
    if constexpr (requires { x.source; }) return x.source;
    else return {};
  }, e);
}

}  // namespace

OdometryCoalescer::OdometryCoalescer(const OdometryCoalescerOptions& options) : options_(options) {
  if (options_.max_entries == 0) options_.max_entries = 1;
  if (options_.max_passed == 0) options_.max_passed = 1;
  KeyframeSelector check(options_.keyframes);  // throws std::invalid_argument for bad thresholds
  (void)check;
}

OdometryCoalescer::Entry OdometryCoalescer::make_entry(const Body& b, const Odometry& o, KeyframeDecision d,
                                                       bool pinned) const {
  Entry e;
  e.message = o;
  e.pinned = pinned;
  e.decision = d;
  e.selector = b.selector;
  if (b.has_last) {
    const SE3 pose = to_se3(o.pose);
    e.increment = increment_covariance(o, b.last_pose.between(pose), b.last_covariance, options_.min_increment_variance);
  }
  return e;
}

bool OdometryCoalescer::offer(const Event& event, const std::function<bool()>& enqueue) {
  const auto* o = std::get_if<Odometry>(&event);
  if (o == nullptr) {
    // A loop, a sighting or anything else of a body: its odometry after this event goes into a new batch behind it.
    // Queued first: an event the queue refuses leaves no trace here (the open batch stays open, so the odometry that
    // follows still needs no queue slot, and its time pins nothing).  Only this (intake) thread offers, so nothing is
    // appended to the batch between the two steps; the stage may take the batch meanwhile, which closes it anyway.
    if (!enqueue()) return false;
    {
      std::lock_guard lock(mutex_);
      auto it = bodies_.find(source_of(event));
      if (it != bodies_.end()) {
        Body& b = it->second;
        b.open = false;
        // The stage takes up a sighting or a loop ahead of the odometry at the first message at or after its time
        // (a loop: after both of its times): that message is pinned, so that it happens at the same message.
        std::optional<int64_t> waits_for;
        if (const auto* s = std::get_if<LandmarkSightings>(&event)) waits_for = s->utime;
        if (const auto* l = std::get_if<LoopClosure>(&event)) waits_for = std::max(l->utime_from, l->utime_to);
        if (waits_for && (!b.has_last || *waits_for > b.last_utime) && b.waiting_times.size() < kMaxWaitingTimes)
          b.waiting_times.insert(std::upper_bound(b.waiting_times.begin(), b.waiting_times.end(), *waits_for), *waits_for);
      }
    }
    return true;
  }

  std::lock_guard lock(mutex_);
  auto it = bodies_.find(o->source);
  if (it == bodies_.end()) {
    KeyframeSelectorOptions ko = options_.keyframes;
    ko.planar = o->planar;
    Body body;
    body.selector = KeyframeSelector(ko);
    it = bodies_.emplace(o->source, std::move(body)).first;
  }
  Body& b = it->second;
  if (b.has_last && o->utime <= b.last_utime) {
    ++out_of_order_;  // the stage would count and drop it too (odometry_out_of_order)
    return true;
  }
  const SE3 pose = to_se3(o->pose);
  KeyframeSelector selector = b.selector;  // decided on a copy: a message the queue refuses leaves no trace
  const KeyframeDecision d = selector.decide(pose);
  const bool after_waiting = !b.waiting_times.empty() && b.waiting_times.front() <= o->utime;
  const bool pinned = d == KeyframeDecision::kKeyframe || d == KeyframeDecision::kReanchored || after_waiting;

  bool taken = true;
  if (b.open && !b.batches.back().back().pinned) {
    // Merge into the newest message: its time and pose go to `passed`, the increments' covariances compose.
    Entry& e = b.batches.back().back();
    const SE3 delta = b.last_pose.between(pose);
    const Matrix6 q = increment_covariance(*o, delta, b.last_covariance, options_.min_increment_variance);
    if (e.passed.size() >= options_.max_passed)
      e.passed.erase(e.passed.begin(), e.passed.begin() + static_cast<std::ptrdiff_t>(e.passed.size() / 2));
    e.passed.emplace_back(e.message.utime, b.last_pose);
    if (e.decision == KeyframeDecision::kImplausible) ++e.implausible;
    e.increment = compose_covariance(e.increment, delta, q);
    e.message = *o;
    e.message.increment_covariance = e.increment - variance_floor(o->planar, options_.min_increment_variance);
    e.decision = d;
    e.selector = b.selector;
    e.pinned = pinned;
    ++coalesced_;
  } else if (b.open && b.batches.back().size() < options_.max_entries) {
    b.batches.back().push_back(make_entry(b, *o, d, pinned));
    ++waiting_;
  } else {
    // A new batch behind everything queued so far; the event itself is its token.
    b.batches.push_back(Batch{make_entry(b, *o, d, pinned)});
    taken = enqueue();
    if (!taken) {
      b.batches.pop_back();
      b.open = false;
      return false;  // dropped (the queue counts it): the body's state stays as it was before this message
    }
    b.open = true;
    ++waiting_;
  }
  b.selector = selector;
  b.has_last = true;
  b.last_utime = o->utime;
  b.last_pose = pose;
  b.last_covariance = o->covariance;
  if (after_waiting)
    b.waiting_times.erase(b.waiting_times.begin(),
                           std::upper_bound(b.waiting_times.begin(), b.waiting_times.end(), o->utime));
  return taken;
}

std::optional<OdometryCoalescer::Batch> OdometryCoalescer::take(const std::string& source) {
  std::lock_guard lock(mutex_);
  auto it = bodies_.find(source);
  if (it == bodies_.end() || it->second.batches.empty()) return std::nullopt;
  Body& b = it->second;
  Batch batch = std::move(b.batches.front());
  b.batches.pop_front();
  if (b.batches.empty()) b.open = false;  // its token has been handled: the next message needs a new one
  waiting_ -= static_cast<int64_t>(batch.size());
  return batch;
}

void OdometryCoalescer::keyframe_dropped(const std::string& source, const SE3& dropped, const std::optional<SE3>& reference) {
  std::lock_guard lock(mutex_);
  auto it = bodies_.find(source);
  if (it != bodies_.end() && it->second.selector.refers_to(dropped)) it->second.selector.reset_reference(reference);
}

int64_t OdometryCoalescer::coalesced() const {
  std::lock_guard lock(mutex_);
  return coalesced_;
}

int64_t OdometryCoalescer::out_of_order() const {
  std::lock_guard lock(mutex_);
  return out_of_order_;
}

int64_t OdometryCoalescer::waiting() const {
  std::lock_guard lock(mutex_);
  return waiting_;
}

void OdometryCoalescer::resume(const std::string& source, const KeyframeSelector& selector, int64_t last_utime,
                               const SE3& last_pose, const Matrix6& last_covariance) {
  std::lock_guard lock(mutex_);
  Body& b = bodies_[source];
  b.selector = selector;
  b.has_last = true;
  b.last_utime = last_utime;
  b.last_pose = last_pose;
  b.last_covariance = last_covariance;
}

void OdometryCoalescer::forget(const std::string& source) {
  std::lock_guard lock(mutex_);
  if (auto it = bodies_.find(source); it != bodies_.end() && it->second.batches.empty()) bodies_.erase(it);
}

}  // namespace sextant::engine
