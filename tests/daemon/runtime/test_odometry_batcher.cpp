// The odometry batcher on its own (a queue of slots in the test, no thread): one queue slot per batch, arrival order
// per body, the batch bound, a refused token and a refused event, the bounds on waiting messages; and behind a real
// stage thread, every message handled once, in each body's order.
#include "daemon/runtime/odometry_batcher.hpp"
#include "daemon/stage_counters.hpp"
#include "daemon/runtime/stage_runner.hpp"

#include <doctest/doctest.h>

#include <deque>
#include <map>
#include <random>
#include <string>
#include <thread>
#include <variant>
#include <vector>

using namespace sextant;
using runtime::OdometryBatcher;
using runtime::QueuedEvent;

using sextant::stage_counters::counter;

namespace {

QueuedEvent odometry(const std::string& source, int64_t utime) {
  engine::Odometry o;
  o.utime = utime;
  o.source = source;
  return {o, std::chrono::steady_clock::now()};
}

QueuedEvent loop(const std::string& source, int64_t utime) {
  engine::LoopClosure l;
  l.utime = utime;
  l.source = source;
  return {l, std::chrono::steady_clock::now()};
}

std::string name_of(const QueuedEvent& e) {
  const char* kind = std::holds_alternative<engine::Odometry>(e.event) ? "o" : "l";
  return engine::event_source(e.event) + ":" + kind + std::to_string(engine::event_utime(e.event));
}

// The stage's queue as the runner holds it (an event or a batch's token), bounded, and the stage's side: pop every
// slot, a token's batch message by message.
struct Queue {
  size_t capacity = 1024;
  std::deque<std::variant<QueuedEvent, OdometryBatcher::Token>> slots;
  size_t peak = 0, refused = 0;

  bool push(std::variant<QueuedEvent, OdometryBatcher::Token> slot) {
    if (slots.size() >= capacity) {
      ++refused;
      return false;
    }
    slots.push_back(std::move(slot));
    peak = std::max(peak, slots.size());
    return true;
  }
  bool offer(OdometryBatcher& b, const QueuedEvent& e) {
    return b.offer(
        e, [&](const QueuedEvent& x) { return push(x); }, [&](const OdometryBatcher::Token& t) { return push(t); });
  }
  // Pops one slot: what the stage handles for it, in order.
  std::vector<std::string> pop(OdometryBatcher& b) {
    std::vector<std::string> out;
    auto slot = std::move(slots.front());
    slots.pop_front();
    if (const auto* e = std::get_if<QueuedEvent>(&slot))
      out.push_back(name_of(*e));
    else
      for (const auto& m : b.take(std::get<OdometryBatcher::Token>(slot))) out.push_back(name_of(m));
    return out;
  }
  std::vector<std::vector<std::string>> drain(OdometryBatcher& b) {
    std::vector<std::vector<std::string>> out;
    while (!slots.empty()) out.push_back(pop(b));
    return out;
  }
};

using Slots = std::vector<std::vector<std::string>>;

}  // namespace

TEST_CASE("odometry batcher: a body's odometry waits behind one queue slot, its other events close the batch") {
  OdometryBatcher b(runtime::OdometryBatcherOptions{});
  Queue q;
  for (const auto& e : {odometry("a", 1), odometry("b", 2), odometry("a", 3), odometry("a", 4), loop("a", 5),
                        odometry("b", 6), odometry("a", 7), loop("b", 8), odometry("a", 9), odometry("b", 10)})
    CHECK(q.offer(b, e));
  CHECK(q.slots.size() == 6);
  CHECK(b.coalesced() == 4);  // a:3, a:4, b:6, a:9
  CHECK(b.waiting() == 8);
  // Per body the arrival order; a's loop after a:4 and before a:7, b's loop after b:6 and before b:10.
  CHECK(q.drain(b) ==
        Slots{{"a:o1", "a:o3", "a:o4"}, {"b:o2", "b:o6"}, {"a:l5"}, {"a:o7", "a:o9"}, {"b:l8"}, {"b:o10"}});
  CHECK(b.waiting() == 0);
  CHECK(b.coalesced() == 4);
  CHECK(b.dropped() == 0);
}

TEST_CASE("odometry batcher: a taken batch takes no more, a full batch opens the next one") {
  runtime::OdometryBatcherOptions o;
  o.max_batch = 3;
  OdometryBatcher b(o);
  Queue q;
  for (int64_t t = 1; t <= 7; ++t) CHECK(q.offer(b, odometry("a", t)));
  CHECK(q.slots.size() == 3);  // 3 + 3 + 1 messages
  CHECK(q.pop(b) == std::vector<std::string>{"a:o1", "a:o2", "a:o3"});
  CHECK(q.offer(b, odometry("a", 8)));  // joins the newest batch, still waiting
  CHECK(q.pop(b) == std::vector<std::string>{"a:o4", "a:o5", "a:o6"});
  CHECK(q.pop(b) == std::vector<std::string>{"a:o7", "a:o8"});
  CHECK(q.slots.empty());
  CHECK(q.offer(b, odometry("a", 9)));  // the stage has taken every batch: a new slot
  CHECK(q.slots.size() == 1);
  CHECK(b.take(std::get<OdometryBatcher::Token>(q.slots.front())).size() == 1);
  CHECK(b.take(std::get<OdometryBatcher::Token>(q.slots.front())).empty());  // taken once
  CHECK(b.waiting() == 0);
  CHECK(b.coalesced() == 5);
}

TEST_CASE("odometry batcher: a token the queue refuses drops its message, an event the queue refuses closes nothing") {
  OdometryBatcher b(runtime::OdometryBatcherOptions{});
  Queue q;
  q.capacity = 2;
  CHECK(q.offer(b, odometry("a", 1)));
  CHECK(q.offer(b, loop("a", 2)));            // closes a's batch
  CHECK_FALSE(q.offer(b, odometry("a", 3)));  // a new batch: its token is refused, the message dropped
  CHECK(q.refused == 1);
  CHECK(b.waiting() == 1);
  CHECK(q.pop(b) == std::vector<std::string>{"a:o1"});
  CHECK(q.offer(b, odometry("a", 4)));    // a slot again
  CHECK_FALSE(q.offer(b, loop("a", 5)));  // refused: as if it had never come
  CHECK(q.refused == 2);
  CHECK(q.offer(b, odometry("a", 6)));  // still joins a:4's batch, needs no slot
  CHECK(q.offer(b, odometry("a", 7)));
  CHECK(q.drain(b) == Slots{{"a:l2"}, {"a:o4", "a:o6", "a:o7"}});
  CHECK(b.dropped() == 0);  // the queue counts what it refused
}

TEST_CASE("odometry batcher: at most max_waiting_per_body messages of a body and max_waiting of all wait") {
  runtime::OdometryBatcherOptions o;
  o.max_batch = 4;
  o.max_waiting_per_body = 6;
  o.max_waiting = 10;
  OdometryBatcher b(o);
  Queue q;
  int accepted_a = 0, accepted_b = 0, accepted_c = 0;
  for (int64_t t = 1; t <= 20; ++t) accepted_a += q.offer(b, odometry("a", t)) ? 1 : 0;
  for (int64_t t = 1; t <= 20; ++t) accepted_b += q.offer(b, odometry("b", t)) ? 1 : 0;
  for (int64_t t = 1; t <= 20; ++t) accepted_c += q.offer(b, odometry("c", t)) ? 1 : 0;
  CHECK(accepted_a == 6);  // a's own bound
  CHECK(accepted_b == 4);  // the total bound (6 + 4 = 10)
  CHECK(accepted_c == 0);
  CHECK(b.waiting() == 10);
  CHECK(b.dropped() == 14 + 16 + 20);
  CHECK(q.refused == 0);
  // A body's events other than odometry are not bounded here (the queue bounds them).
  CHECK(q.offer(b, loop("c", 1)));
  // Once the stage took a's first batch (4 messages), 4 messages more may wait.
  CHECK(q.pop(b) == std::vector<std::string>{"a:o1", "a:o2", "a:o3", "a:o4"});
  CHECK(q.offer(b, odometry("c", 21)));
  CHECK(q.offer(b, odometry("a", 21)));
  CHECK(q.offer(b, odometry("a", 22)));
  CHECK(q.offer(b, odometry("a", 23)));
  CHECK_FALSE(q.offer(b, odometry("a", 24)));  // the total again
  CHECK(b.waiting() == 10);
  q.drain(b);
  CHECK(b.waiting() == 0);
  CHECK_THROWS_AS(OdometryBatcher(runtime::OdometryBatcherOptions{0, 1, 1}), std::invalid_argument);
}

namespace {

// Records what it handled, per body, and now and then takes its time (so that the queue fills and batches grow).
class RecordingStage final : public engine::Stage {
 public:
  engine::StageKind kind() const override { return engine::StageKind::kOther; }
  std::string_view name() const override { return "recording"; }
  bool accepts(const engine::Event&) const override { return true; }
  void handle(const engine::Event& e, const engine::Emit&) override {
    handled[engine::event_source(e)].push_back(engine::event_utime(e));
    if (++count % 97 == 0) std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  std::map<std::string, std::vector<int64_t>> handled;
  int64_t count = 0;
};

}  // namespace

TEST_CASE(
    "odometry batcher behind a stage thread: every message handled once, in its body's order, or counted as dropped") {
  RecordingStage stage;
  runtime::OdometryBatcherOptions o;
  o.max_batch = 16;
  runtime::StageRunner runner(
      stage, 32, [](engine::Output) {}, o);
  runner.start();
  std::mt19937 rng(3);
  std::map<std::string, std::vector<int64_t>> accepted;
  int64_t offered = 0, refused = 0;
  for (int64_t t = 1; t <= 20000; ++t) {
    const std::string body = "body" + std::to_string(rng() % 3);
    const QueuedEvent e = rng() % 50 == 0 ? loop(body, t) : odometry(body, t);
    ++offered;
    if (runner.offer(e))
      accepted[body].push_back(t);
    else
      ++refused;
    if (t % 100 == 0) std::this_thread::sleep_for(std::chrono::microseconds(300));  // bursts of 100 messages
  }
  runner.drain_and_stop();
  const auto s = runner.status();
  CHECK(stage.handled == accepted);
  CHECK(s.processed == offered - refused);
  CHECK(s.dropped == refused);
  CHECK(counter(s, "odometry_waiting") == 0);
  CHECK(counter(s, "odometry_coalesced") > 0);
  MESSAGE("offered " << offered << ", refused " << refused << ", joined a waiting batch "
                     << counter(s, "odometry_coalesced"));
}
