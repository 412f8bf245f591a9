// The fleet exchange between daemons (daemon/engine/fleet_exchange.hpp): numbering, batching under the datagram size,
// loss repair over a lossy, reordering, duplicating bus, a long cut, a restart from saved state, and senders that are
// not to be believed.  Each run asserts that a receiver delivers exactly the owner's stream, in order, where the
// scheme promises it, and bounded memory and counts otherwise.
#include "daemon/engine/fleet_exchange.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <random>
#include <string>
#include <vector>

using namespace sextant;
using namespace sextant::engine;
using namespace sextant::engine::fleet;

namespace {

FleetExchangeOptions options(std::vector<std::string> members = {"a", "b", "c"}) {
  FleetExchangeOptions o;
  o.enabled = true;
  o.members = std::move(members);
  return o;
}

slam::GraphContribution keyframe(const std::string& body, int64_t id) {
  slam::KeyframeContribution k;
  k.id = id;
  k.utime = 1000000 * id;
  k.first = id == 0;
  k.odom_covariance = Matrix6d::Identity() * 0.01;
  k.edge_covariance = Matrix6d::Identity() * 0.001;
  return {body, k};
}

slam::GraphContribution sightings(const std::string& body, int64_t keyframe_id, size_t n) {
  slam::SightingsContribution s;
  s.anchor.keyframe = keyframe_id;
  s.sightings.utime = 1000000 * keyframe_id + 10;
  for (size_t i = 0; i < n; ++i) {
    slam::LandmarkSighting l;
    l.id = static_cast<int64_t>(i);
    l.range = 1.0 + static_cast<double>(i);
    l.covariance = Eigen::Matrix3d::Identity() * 0.01;
    s.sightings.sightings.push_back(l);
  }
  return {body, s};
}

// What identifies a test contribution: its kind, keyframe id and time, and its sightings' first id and count.
std::string key(const What& w) {
  if (const auto* k = std::get_if<slam::KeyframeContribution>(&w)) return "k" + std::to_string(k->id);
  if (const auto* s = std::get_if<slam::SightingsContribution>(&w))
    return "s" + std::to_string(s->anchor.keyframe) + "/" + std::to_string(s->sightings.sightings.front().id) + "+" +
           std::to_string(s->sightings.sightings.size());
  return "?";
}

// A bus between daemons: each message is lost with probability `loss`, delivered twice with `duplicate`, and what
// is delivered in one step arrives in a random order.  `cut` drops everything.
struct Bus {
  std::mt19937 rng;
  double loss = 0, duplicate = 0;
  bool cut = false;
  template <class M>
  std::vector<M> carry(std::vector<M> in) {
    std::vector<M> out;
    std::uniform_real_distribution<double> u(0, 1);
    for (auto& m : in) {
      if (cut || u(rng) < loss) continue;
      if (u(rng) < duplicate) out.push_back(m);
      out.push_back(std::move(m));
    }
    std::shuffle(out.begin(), out.end(), rng);
    return out;
  }
};

// Daemon a owns body r1 and contributes; daemon b receives.  One step is 0.1 s.
struct Pair {
  FleetExchange a{"a", options()}, b{"b", options()};
  Bus bus{std::mt19937(7)};
  std::vector<std::string> sent, delivered;
  int64_t now = 1000000;
  int64_t next_id = 0;

  void contribute(int keyframes) {
    for (int i = 0; i < keyframes; ++i) {
      const int64_t id = next_id++;
      for (auto c : {keyframe("r1", id), sightings("r1", id, 3)}) {
        sent.push_back(key(c.what));
        a.contributed(c);
      }
    }
  }
  void step(int keyframes = 0) {
    now += 100000;
    contribute(keyframes);
    auto due = a.due(now);
    for (auto& m : bus.carry(due.contributions)) take(b.inbox.receive(m, now));
    for (auto& h : bus.carry(due.control)) take(b.inbox.receive(h, now));
    for (auto& request : bus.carry(b.due(now).control))
      for (auto& answer : bus.carry(a.outbox.answer(request, now))) take(b.inbox.receive(answer, now));
  }
  void take(const std::vector<slam::GraphContribution>& got) {
    for (const auto& c : got) {
      CHECK(c.body == "r1");
      delivered.push_back(key(c.what));
    }
  }
};

}  // namespace

TEST_CASE(
    "fleet exchange: numbering from 1 per body, a big sightings message split with its anchor, messages under the "
    "size") {
  Outbox out("a", options());
  out.add(keyframe("r1", 0));
  out.add(sightings("r1", 0, 600));
  out.add(keyframe("r2", 0));
  CHECK(out.next_seq("r1") == 5);  // the keyframe, then 256 + 256 + 88 sightings
  CHECK(out.next_seq("r2") == 2);
  const auto msgs = out.take_messages(5);
  REQUIRE(msgs.size() >= 2);
  std::vector<int64_t> firsts;
  for (const auto& m : msgs) {
    size_t bytes = message_overhead_bytes(m.sender, m.body);
    for (const auto& w : m.contributions) bytes += item_bytes(w);
    CHECK(bytes <= 60000);
    CHECK(m.sender == "a");
    if (m.body == "r1") firsts.push_back(m.first);
  }
  CHECK(firsts.front() == 1);
  std::vector<size_t> parts;
  for (const auto& m : msgs)
    for (const auto& w : m.contributions)
      if (const auto* s = std::get_if<slam::SightingsContribution>(&w)) {
        CHECK(s->anchor.keyframe == 0);
        parts.push_back(s->sightings.sightings.size());
      }
  CHECK(parts == std::vector<size_t>{256, 256, 88});
  CHECK(out.take_messages(6).empty());  // each sent once
  CHECK(split_for_wire(sightings("r1", 0, 0).what).empty());
  slam::KeyframesThinned thinned;
  for (int64_t id = 0; id < 2500; ++id) thinned.keyframes.push_back(id);
  const auto pieces = split_for_wire(thinned);
  REQUIRE(pieces.size() == 3);
  CHECK(std::get<slam::KeyframesThinned>(pieces[2]).keyframes.size() == 452);
  CHECK(std::get<slam::KeyframesThinned>(pieces[1]).keyframes.front() == 1024);
}

TEST_CASE("fleet exchange: the stream arrives whole and in order through loss, reordering and duplication") {
  for (const double loss : {0.1, 0.3, 0.5}) {
    CAPTURE(loss);
    Pair p;
    p.bus.loss = loss;
    p.bus.duplicate = 0.2;
    for (int i = 0; i < 300; ++i) p.step(i % 3 == 0 ? 2 : 0);
    for (int i = 0; i < 600 && p.delivered.size() < p.sent.size(); ++i) p.step();
    CHECK(p.delivered == p.sent);
    CHECK(p.b.inbox.held() == 0);
    CHECK(p.b.inbox.counters().lost == 0);
    CHECK(p.b.inbox.counters().repair_requests > 0);
  }
}

TEST_CASE("fleet exchange: a lost tail is found from the heartbeat, and asked for with a back-off") {
  Pair p;
  p.contribute(1);
  (void)p.a.due(p.now);  // sent, and lost on the way
  p.now += 100000;
  for (auto& h : p.a.outbox.heartbeat(p.now + 5000000)) CHECK(p.b.inbox.receive(h, p.now).empty());
  CHECK(p.b.inbox.repair_requests(p.now).empty());  // not before the back-off
  std::vector<int64_t> asked;
  for (int64_t t = p.now; t < p.now + 4000000; t += 10000)
    if (auto r = p.b.inbox.repair_requests(t); !r.empty()) {
      CHECK(r.size() == 1);
      CHECK(r[0].daemon == "a");
      CHECK(r[0].streams[0].first == 1);
      CHECK(r[0].streams[0].last == 2);
      asked.push_back(t);
    }
  REQUIRE(asked.size() >= 3);
  CHECK(asked[2] - asked[1] > asked[1] - asked[0]);  // backing off
  const auto answer = p.a.outbox.answer(p.b.inbox.repair_requests(p.now + 10000000)[0], p.now);
  REQUIRE(answer.size() == 1);
  CHECK(answer[0].repair);
  CHECK(p.b.inbox.receive(answer[0], p.now).size() == 2);
  CHECK(p.b.inbox.repair_requests(p.now + 20000000).empty());
}

TEST_CASE("fleet exchange: a gap is asked for again as soon as its owner is heard after a silence") {
  for (const bool heard : {false, true}) {
    CAPTURE(heard);
    Pair p;
    p.contribute(1);
    (void)p.a.due(p.now);                                                               // sent, and lost on the way
    for (auto& h : p.a.outbox.heartbeat(p.now + 5000000)) p.b.inbox.receive(h, p.now);  // b learns of the gap
    // The owner is cut off: b's requests go unanswered and its back-off grows to repair_backoff_max_s.
    int64_t last_ask = 0;
    for (int64_t t = p.now; t < p.now + 10000000; t += 10000)
      if (!p.b.inbox.repair_requests(t).empty()) last_ask = t;
    REQUIRE(last_ask > p.now + 5000000);
    const int64_t healed = last_ask + 500000;
    if (heard)
      for (auto& h : p.a.outbox.heartbeat(healed + 20000000)) p.b.inbox.receive(h, healed);
    CHECK(p.b.inbox.repair_requests(healed + 200001).empty() == !heard);  // else: 5 s after the last request
  }
}

TEST_CASE("fleet exchange: after a long cut the stream resumes from repairs, at the requester's rate") {
  Pair p;
  p.bus.loss = 0.1;
  for (int i = 0; i < 100; ++i) p.step(1);
  p.bus.cut = true;
  for (int i = 0; i < 3000; ++i) p.step(i % 2);  // five minutes apart
  p.bus.cut = false;
  const int64_t resent_before = p.a.outbox.counters().repaired;
  for (int i = 0; i < 3000 && p.delivered.size() < p.sent.size(); ++i) p.step();
  CHECK(p.delivered == p.sent);
  CHECK(p.b.inbox.counters().lost == 0);
  CHECK(p.a.outbox.counters().repaired - resent_before >= 1500 * 2);
  CHECK(p.a.outbox.counters().repair_limited > 0);  // the backlog came at the rate, not at once
}

TEST_CASE("fleet exchange: beyond `retain` the missing part is counted lost and the stream resumes with what is left") {
  Pair p;
  auto o = options();
  o.retain = 50;
  p.a = FleetExchange("a", o);
  for (int i = 0; i < 20; ++i) p.step(1);
  p.bus.cut = true;
  for (int i = 0; i < 100; ++i) p.step(1);
  p.bus.cut = false;
  for (int i = 0; i < 200; ++i) p.step();
  const auto& c = p.b.inbox.counters();
  CHECK(c.lost > 0);
  CHECK(static_cast<int64_t>(p.delivered.size()) + c.lost == static_cast<int64_t>(p.sent.size()));
  // What was delivered is the sent stream with a hole: a prefix, then the last 50 the owner kept.
  const size_t tail = 50;
  REQUIRE(p.delivered.size() >= tail);
  CHECK(std::equal(p.delivered.end() - tail, p.delivered.end(), p.sent.end() - tail));
  CHECK(std::equal(p.delivered.begin(), p.delivered.begin() + 40, p.sent.begin()));
  CHECK(p.a.outbox.first_retained("r1") == p.a.outbox.next_seq("r1") - 50);
  CHECK(p.b.inbox.held() == 0);
}

TEST_CASE("fleet exchange: a receiver restarted from saved state asks only for what it missed") {
  Pair p;
  p.bus.loss = 0.2;
  for (int i = 0; i < 100; ++i) p.step(1);
  for (int i = 0; i < 100; ++i) p.step();  // caught up
  REQUIRE(p.delivered == p.sent);
  archive::ArchiveWriter w;
  p.b.save(w);
  const std::string saved = w.data();
  const size_t at_save = p.delivered.size();
  for (int i = 0; i < 50; ++i) p.step(1);  // then killed: what it received since is lost with it
  p.delivered.resize(at_save);
  const auto missed = static_cast<int64_t>(p.sent.size() - at_save);
  FleetExchange restarted("b", options());
  archive::ArchiveReader r(saved.data(), saved.size(), "state");
  restarted.load(r);
  r.expect_end();
  p.b = std::move(restarted);
  CHECK(p.b.inbox.next_expected("r1") == static_cast<int64_t>(at_save) + 1);
  // The owner's next heartbeat shows the restarted daemon its gap: it asks from where its state ends, not from 1.
  p.now += 100000;
  for (const auto& h : p.a.outbox.heartbeat(p.now + 10000000)) CHECK(p.b.inbox.receive(h, p.now).empty());
  const auto requests = p.b.inbox.repair_requests(p.now + 1000000);
  REQUIRE(requests.size() == 1);
  REQUIRE(requests[0].streams.size() == 1);
  CHECK(requests[0].streams[0].first == static_cast<int64_t>(at_save) + 1);
  CHECK(requests[0].streams[0].last == static_cast<int64_t>(p.sent.size()));
  CHECK(missed == 100);
  for (int i = 0; i < 600 && p.delivered.size() < p.sent.size(); ++i) p.step(i < 20 ? 1 : 0);
  CHECK(p.delivered == p.sent);
}

TEST_CASE("fleet exchange: an owner restarted from saved state continues its numbering and answers from its log") {
  Pair p;
  for (int i = 0; i < 30; ++i) p.step(1);
  archive::ArchiveWriter w;
  p.a.save(w);
  FleetExchange restarted("a", options());
  archive::ArchiveReader r(w.data().data(), w.data().size(), "state");
  restarted.load(r);
  r.expect_end();
  CHECK(restarted.outbox.next_seq("r1") == p.a.outbox.next_seq("r1"));
  CHECK(restarted.outbox.first_retained("r1") == 1);
  FleetControl ask{p.now, "c", FleetControl::Kind::kRepair, "a", {FleetRange{"r1", 1, 60}}};
  const auto answer = restarted.outbox.answer(ask, p.now);
  REQUIRE(!answer.empty());
  Inbox late("c", options());  // a daemon that joins late gets the stream from the start
  for (const auto& h : restarted.outbox.heartbeat(p.now)) (void)late.receive(h, p.now);  // known from its owner
  std::vector<std::string> got;
  for (const auto& m : answer)
    for (const auto& c : late.receive(m, p.now)) got.push_back(key(c.what));
  CHECK(got == p.sent);
  CHECK(restarted.inbox.owner("r1").empty());
  CHECK(restarted.inbox.own("r1"));  // still its own body
}

TEST_CASE("fleet exchange: damaged saved state is refused, never half-loaded") {
  Pair p;
  for (int i = 0; i < 5; ++i) p.step(1);
  archive::ArchiveWriter w;
  p.b.save(w);
  std::string bytes = w.data();
  for (size_t cut : {size_t{3}, bytes.size() / 2, bytes.size() - 1}) {
    FleetExchange fresh("b", options());
    archive::ArchiveReader r(bytes.data(), cut, "state");
    CHECK_THROWS_AS(fresh.load(r), archive::ArchiveError);
  }
}

TEST_CASE("fleet exchange: senders that are not to be believed cannot open streams, take bodies or grow memory") {
  auto o = options();
  o.max_streams_per_sender = 4;
  Inbox in("b", o);
  REQUIRE(in.own("mine"));
  const auto msg = [](std::string sender, std::string body, int64_t first) {
    FleetContributions m;
    m.sender = std::move(sender);
    m.body = std::move(body);
    m.first = first;
    m.contributions.push_back(keyframe(m.body, first).what);
    return m;
  };
  CHECK(in.receive(msg("mallory", "r9", 1), 1).empty());  // not a member
  CHECK(in.receive(msg("b", "r9", 1), 1).empty());        // its own, back from multicast
  CHECK(in.receive(msg("a", "mine", 1), 1).empty());      // a local body
  CHECK(in.receive(msg("a", "r1", 1), 1).size() == 1);
  CHECK(in.receive(msg("c", "r1", 2), 1).empty());  // r1 is a's
  CHECK(in.owner("r1") == "a");
  CHECK(in.receive(msg("a", "r1", int64_t{1} << 61), 1).empty());  // a number far ahead: not held
  CHECK(in.receive(msg("a", "r1", INT64_MAX), 1).empty());
  CHECK(in.held() == 0);
  for (int i = 0; i < 1000; ++i) (void)in.receive(msg("c", "flood" + std::to_string(i), 1), 1);
  CHECK(in.streams() == 1 + 4);
  FleetControl hb{1, "mallory", FleetControl::Kind::kHeartbeat, "", {FleetRange{"r7", 1, 1000}}};
  CHECK(in.receive(hb, 1).empty());
  CHECK(in.repair_requests(100000000).empty());
  const auto& c = in.counters();
  CHECK(c.not_member == 2);
  CHECK(c.own == 1);
  CHECK(c.local_body == 1);
  CHECK(c.claimed == 1);
  CHECK(c.out_of_window == 2);
  CHECK(c.too_many_streams == 1000 - 4);
  CHECK(in.next_expected("r1") == 2);
  CHECK(!in.own("r1"));  // a's: this daemon's sensors of r1 would be a second owner
}

TEST_CASE("fleet exchange: repair requests are answered within each requester's rate, members only") {
  auto o = options();
  o.repair_bytes_per_s = 100000;
  Outbox out("a", o);
  for (int64_t i = 0; i < 2000; ++i) out.add(keyframe("r1", i));
  (void)out.take_messages(0);
  const auto bytes_of = [](const std::vector<FleetContributions>& msgs) {
    size_t n = 0;
    for (const auto& m : msgs) {
      n += message_overhead_bytes(m.sender, m.body);
      for (const auto& w : m.contributions) n += item_bytes(w);
    }
    return n;
  };
  FleetControl storm{0, "b", FleetControl::Kind::kRepair, "a", {FleetRange{"r1", 1, 2000}}};
  size_t answered = 0;
  for (int64_t t = 0; t <= 10000000; t += 1000) answered += bytes_of(out.answer(storm, t));  // 1000 requests a second
  CHECK(answered <= 100000 * 11 + 60000);  // the rate over 10 s and one bucket
  CHECK(answered >= 100000 * 9);
  CHECK(out.counters().repair_limited > 0);
  FleetControl stranger{0, "mallory", FleetControl::Kind::kRepair, "a", {FleetRange{"r1", 1, 10}}};
  CHECK(out.answer(stranger, 20000000).empty());
  FleetControl other{0, "b", FleetControl::Kind::kRepair, "c", {FleetRange{"r1", 1, 10}}};
  CHECK(out.answer(other, 20000000).empty());  // addressed to c
  FleetControl unknown{0, "b", FleetControl::Kind::kRepair, "a", {FleetRange{"r5", 1, 10}}};
  CHECK(out.answer(unknown, 20000000).empty());
  CHECK(out.counters().repair_refused == 2);
  // One request asks for max_repair_range contributions at most.
  FleetControl wide{0, "c", FleetControl::Kind::kRepair, "a", {FleetRange{"r1", 1, INT64_MAX}}};
  size_t n = 0;
  for (const auto& m : out.answer(wide, 30000000)) n += m.contributions.size();
  CHECK(n <= 1024);
}

TEST_CASE("fleet exchange: the retained log is bounded by count and by size") {
  auto o = options();
  o.retain = 100;
  o.retain_mb = 1;
  Outbox out("a", o);
  for (int64_t i = 0; i < 1000; ++i) {
    out.add(keyframe("r1", i));
    (void)out.take_messages(i);
  }
  CHECK(out.next_seq("r1") - out.first_retained("r1") == 100);
  for (int64_t i = 0; i < 100; ++i) {
    out.add(sightings("r1", 999, 256));
    (void)out.take_messages(i);
  }
  const int64_t kept = out.next_seq("r1") - out.first_retained("r1");
  CHECK(kept * static_cast<int64_t>(item_bytes(sightings("r1", 0, 256).what)) <= (1 << 20));
  CHECK(out.counters().evicted == 1100 - kept);
}

TEST_CASE("fleet exchange: an owner restarted from an older state than it sent is seen by the others") {
  Pair p;
  for (int i = 0; i < 10; ++i) p.step(1);
  archive::ArchiveWriter w;
  p.a.save(w);
  for (int i = 0; i < 10; ++i) p.step(1);  // sent, applied by b, and not in a's saved state
  CHECK(p.b.inbox.counters().owner_rewound == 0);
  FleetExchange restarted("a", options());
  archive::ArchiveReader r(w.data().data(), w.data().size(), "state");
  restarted.load(r);
  p.a = std::move(restarted);
  p.now += 1000000;
  for (const auto& h : p.a.outbox.heartbeat(p.now)) (void)p.b.inbox.receive(h, p.now);
  CHECK(p.b.inbox.counters().owner_rewound == 1);
}

TEST_CASE(
    "fleet exchange: a local contribution the wire's check refuses is numbered as nothing, and the stream goes on") {
  FleetExchange a("a", options()), b("b", options());
  a.set_wire_check([](const What& w) {
    return std::holds_alternative<slam::SightingsContribution>(w) ? std::string("covariance: refused") : std::string();
  });
  CHECK(a.contributed(keyframe("r1", 0)));
  CHECK(a.contributed(sightings("r1", 0, 3)));
  CHECK(a.contributed(keyframe("r1", 1)));
  CHECK(a.outbox.next_seq("r1") == 4);
  CHECK(a.outbox.counters().refused == 1);
  std::vector<slam::GraphContribution> applied;
  for (const auto& m : a.due(1000000).contributions)
    for (auto& c : b.received(m, 1000000).apply) applied.push_back(std::move(c));
  REQUIRE(applied.size() == 3);  // the receiver's stream goes past the refused one
  CHECK(key(applied[0].what) == "k0");
  CHECK(std::get<slam::KeyframesThinned>(applied[1].what).keyframes ==
        std::get<slam::KeyframesThinned>(kNothing).keyframes);
  CHECK(key(applied[2].what) == "k1");
  CHECK(b.inbox.next_expected("r1") == 4);
  // Without a check, the same contribution goes out as it is.
  FleetExchange c("c", options());
  CHECK(c.contributed(sightings("r2", 0, 3)));
  CHECK(c.outbox.counters().refused == 0);
  REQUIRE(c.due(1000000).contributions.size() == 1);
}

TEST_CASE("fleet exchange: one call per fleet event gives what to apply and what to send, and names every counter") {
  FleetExchange a("a", options()), c("c", options());
  CHECK(a.contributed(keyframe("r1", 0)));
  CHECK(a.contributed(keyframe("r1", 1)));
  const auto due = a.due(1000000);
  REQUIRE(due.contributions.size() == 1);
  REQUIRE(due.control.size() == 1);  // the first heartbeat
  const auto got = c.received(due.contributions[0], 1000000);
  CHECK(got.apply.size() == 2);
  CHECK(got.answers.empty());
  CHECK_FALSE(c.contributed(keyframe("r1", 5)));  // a's body: c's contribution of it is not sent
  CHECK(c.outbox.next_seq("r1") == 1);
  const FleetControl ask{2, "c", FleetControl::Kind::kRepair, "a", {FleetRange{"r1", 1, 2}}};
  const auto answer = a.received(ask, 2000000);
  CHECK(answer.apply.empty());
  REQUIRE(answer.answers.size() == 1);
  CHECK(answer.answers[0].repair);
  const auto counters = c.counters();
  CHECK(counters.size() == 37);
  CHECK(std::find(counters.begin(), counters.end(), std::pair<std::string, int64_t>{"fleet_in_delivered", 2}) !=
        counters.end());
  CHECK(std::find(counters.begin(), counters.end(), std::pair<std::string, int64_t>{"fleet_in_claimed", 1}) !=
        counters.end());
}

namespace {

// A restarted owner from `saved`, and one round of its tail fetch at `now` over a lossless bus: its requests go to
// `peers`, their answers back; what it adopted (keys), and whether it sent a heartbeat.
FleetExchange restart(const std::string& name, const std::string& saved, const FleetExchangeOptions& o) {
  FleetExchange restarted(name, o);
  archive::ArchiveReader r(saved.data(), saved.size(), "state");
  restarted.load(r);
  r.expect_end();
  return restarted;
}

struct FetchRound {
  std::vector<std::string> adopted;
  int requests = 0, heartbeats = 0;
};

FetchRound fetch_round(FleetExchange& owner, const std::vector<FleetExchange*>& peers, int64_t now) {
  FetchRound round;
  const FleetExchange::Due due = owner.due(now);
  for (const auto& own : due.own) round.adopted.push_back(key(own.what));  // the wait's end: what was held ahead
  for (const FleetControl& c : due.control) {
    if (c.kind == FleetControl::Kind::kHeartbeat) {
      ++round.heartbeats;
      continue;
    }
    ++round.requests;
    CHECK(c.daemon == c.sender);  // to every member
    for (FleetExchange* peer : peers)
      for (const FleetContributions& m : peer->received(c, now).answers) {
        const auto got = owner.received(m, now);
        CHECK(got.apply.empty());
        for (const auto& own : got.own) round.adopted.push_back(key(own.what));
      }
  }
  return round;
}

}  // namespace

TEST_CASE(
    "fleet exchange: an owner restarted from an older state than it sent takes its tail back from the others, then "
    "numbers after it, and the others see no rewind") {
  Pair p;
  for (int i = 0; i < 10; ++i) p.step(1);
  archive::ArchiveWriter w;
  p.a.save(w);
  const size_t at_save = p.sent.size();
  for (int i = 0; i < 10; ++i) p.step(1);  // sent and applied by b, not in a's saved state
  REQUIRE(p.delivered == p.sent);
  p.a = restart("a", w.data(), options());
  CHECK(p.a.fetching());
  CHECK(p.a.outbox.next_seq("r1") == static_cast<int64_t>(at_save) + 1);
  std::vector<std::string> adopted;
  int requests = 0, rounds = 0;
  for (; p.a.fetching() && rounds < 100; ++rounds) {
    p.now += 100000;
    const FetchRound round = fetch_round(p.a, {&p.b}, p.now);
    if (p.a.fetching()) CHECK(round.heartbeats == 0);  // it would state the stream before what b holds
    requests += round.requests;
    adopted.insert(adopted.end(), round.adopted.begin(), round.adopted.end());
  }
  CHECK(adopted == std::vector<std::string>(p.sent.begin() + static_cast<std::ptrdiff_t>(at_save), p.sent.end()));
  CHECK(p.a.outbox.next_seq("r1") == static_cast<int64_t>(p.sent.size()) + 1);
  CHECK(p.a.tail.counters().adopted == static_cast<int64_t>(p.sent.size() - at_save));
  CHECK(requests >= 2);  // the first is answered in full; the next finds nothing more
  CHECK(requests <= 5);  // then backs off until the wait ends
  CHECK(rounds == 21);   // restart_wait_s after the last contribution taken back
  // The next contributions follow the tail, the heartbeat states what b holds, and b takes the stream on.
  p.next_id = static_cast<int64_t>(p.sent.size()) / 2;
  for (int i = 0; i < 30; ++i) p.step(i < 10 ? 1 : 0);
  CHECK(p.delivered == p.sent);
  CHECK(p.b.inbox.counters().owner_rewound == 0);
  CHECK(p.b.inbox.counters().duplicates == 0);
  // What was taken back is the owner's log again: a late daemon gets the whole stream from it.
  CHECK(p.a.outbox.first_retained("r1") == 1);
}

TEST_CASE("fleet exchange: a receiver's copy of another owner's stream is bounded like the owner's log") {
  auto o = options();
  o.retain = 7;
  FleetExchange a("a", o), b("b", o);
  for (int64_t id = 0; id < 20; ++id) CHECK(a.contributed(keyframe("r1", id)));
  for (const auto& m : a.due(1000000).contributions)
    CHECK(b.received(m, 1000000).apply.size() == m.contributions.size());
  const Retained* copy = b.inbox.copy_of("r1", "a");
  REQUIRE(copy != nullptr);
  CHECK(copy->items.size() == 7);
  CHECK(copy->first() == 14);
  CHECK(copy->last() == 20);
  CHECK(b.inbox.copy_of("r1", "c") == nullptr);  // not c's stream
}

TEST_CASE(
    "fleet exchange: a restarted owner adopts each contribution once from several members, in order from its next "
    "number, and nothing from a non-member or out of order") {
  FleetExchange a("a", options()), b("b", options()), c("c", options());
  for (int64_t id = 0; id < 5; ++id) CHECK(a.contributed(keyframe("r1", id)));
  for (const auto& m : a.due(1000000).contributions) {
    (void)b.received(m, 1000000);
    (void)c.received(m, 1000000);
  }
  archive::ArchiveWriter w;
  a.save(w);
  for (int64_t id = 5; id < 9; ++id) CHECK(a.contributed(keyframe("r1", id)));
  const auto tail = a.due(2000000).contributions;
  for (const auto& m : tail) (void)b.received(m, 2000000);  // c missed the tail
  FleetExchange restarted = restart("a", w.data(), options());
  const auto answer = [&](std::string sender, int64_t first, int64_t id) {
    FleetContributions m{3000000, std::move(sender), "r1", true, first, {keyframe("r1", id).what}};
    return restarted.received(m, 3000000).own.size();
  };
  CHECK(answer("x", 6, 5) == 0);         // a non-member
  CHECK(answer("a", 6, 5) == 0);         // itself (its own repairs brought back: not counted)
  CHECK(answer("b", 8, 7) == 0);         // does not continue the stream (6 is next): held
  CHECK(answer("b", 6 + 4096, 7) == 0);  // beyond the reorder window: dropped
  CHECK(restarted.tail.counters().refused == 1);
  CHECK(restarted.tail.counters().out_of_order == 1);
  CHECK(restarted.outbox.next_seq("r1") == 6);
  int rounds = 0;
  std::vector<std::string> adopted;
  for (int64_t now = 3000000; restarted.fetching() && rounds < 100; now += 100000, ++rounds) {
    const FetchRound round = fetch_round(restarted, {&c, &b}, now);  // c answers nothing, b the tail
    adopted.insert(adopted.end(), round.adopted.begin(), round.adopted.end());
  }
  CHECK(adopted == std::vector<std::string>{"k5", "k6", "k7", "k8"});
  // Answered again by b on a repeated request, or by two members: dropped as duplicates.
  FleetExchange again = restart("a", w.data(), options());
  for (FleetExchange* peer : {&b, &b}) {
    const FleetControl ask{4000000, "a", FleetControl::Kind::kRepair, "a", {FleetRange{"r1", 6, 100}}};
    for (const auto& m : peer->received(ask, 4000000).answers) (void)again.received(m, 4000000);
  }
  CHECK(again.outbox.next_seq("r1") == 10);
  CHECK(again.tail.counters().adopted == 4);
  CHECK(again.tail.counters().duplicates == 4);
  // A non-member's request for a tail is not answered.
  const FleetControl hostile{4000000, "x", FleetControl::Kind::kRepair, "x", {FleetRange{"r1", 1, 100}}};
  CHECK(b.received(hostile, 4000000).answers.empty());
  CHECK(b.outbox.counters().repair_refused == 1);
}

TEST_CASE("fleet exchange: a restarted owner nobody answers waits restart_wait_s, then goes on as before") {
  Pair p;
  for (int i = 0; i < 5; ++i) p.step(1);
  archive::ArchiveWriter w;
  p.a.save(w);
  FleetExchange restarted = restart("a", w.data(), options());
  FleetExchange silent("c", options());  // holds no copy of r1
  int requests = 0, heartbeats = 0, rounds = 0;
  for (int64_t now = 5000000; rounds < 40; now += 100000, ++rounds) {
    const FetchRound round = fetch_round(restarted, {&silent}, now);
    CHECK(round.adopted.empty());
    requests += round.requests;
    heartbeats += round.heartbeats;
    if (round.heartbeats > 0) break;
  }
  CHECK(rounds == 20);   // 2 s of 0.1 s steps
  CHECK(requests == 4);  // at 0, 0.2, 0.6 and 1.4 s: the repairs' back-off
  CHECK(heartbeats == 1);
  CHECK(restarted.outbox.next_seq("r1") == p.a.outbox.next_seq("r1"));
  // Alone in its configuration (no other member), or without a stream of its own, it does not wait at all.
  CHECK_FALSE(restart("a", w.data(), options({"a"})).fetching());
  archive::ArchiveWriter wb;
  p.b.save(wb);
  CHECK_FALSE(restart("b", wb.data(), options()).fetching());
}

TEST_CASE("fleet exchange: the others' answers to a restarted owner open no stream and change none elsewhere") {
  FleetExchange a("a", options()), b("b", options()), c("c", options()), d("d", options({"a", "b", "c", "d"}));
  CHECK(a.contributed(keyframe("r1", 0)));
  for (const auto& m : a.due(1000000).contributions) {
    (void)b.received(m, 1000000);
    (void)c.received(m, 1000000);
  }
  const FleetControl ask{2000000, "a", FleetControl::Kind::kRepair, "a", {FleetRange{"r1", 1, 10}}};
  const auto answers = b.received(ask, 2000000).answers;
  REQUIRE(answers.size() == 1);
  CHECK(answers[0].repair);
  CHECK(c.received(answers[0], 2000000).apply.empty());  // c knows r1 as a's: b's copy is not for it
  CHECK(c.inbox.counters().repairs_overheard == 1);
  CHECK(c.inbox.owner("r1") == "a");
  CHECK(c.inbox.counters().claimed == 0);
  CHECK(d.received(answers[0], 2000000).apply.empty());  // d never heard of r1: b does not become its owner
  CHECK(d.inbox.owner("r1").empty());
  CHECK(a.received(answers[0], 2000000).own.empty());  // a, not restarted, ignores it
  CHECK(a.inbox.counters().repairs_overheard == 1);
}

TEST_CASE(
    "fleet exchange: what a member holds beyond a gap nobody can fill is taken back after a placeholder, and that "
    "member applies the same sequence") {
  FleetExchange a("a", options()), b("b", options());
  for (int64_t id = 0; id < 4; ++id) CHECK(a.contributed(keyframe("r1", id)));
  for (const auto& m : a.due(1000000).contributions) CHECK(b.received(m, 1000000).apply.size() == 4);
  archive::ArchiveWriter w;
  a.save(w);
  for (int64_t id = 4; id < 8; ++id) CHECK(a.contributed(keyframe("r1", id)));  // numbers 5 to 8
  for (const auto& m : a.due(1100000).contributions) REQUIRE(m.contributions.size() == 4);
  // b gets 5, 7 and 8 (6 lost), then a is killed before it resends 6.
  std::vector<std::string> at_b;
  const auto to_b = [&](int64_t seq, int64_t now) {
    FleetContributions m{now, "a", "r1", false, seq, {keyframe("r1", seq - 1).what}};
    for (const auto& c : b.received(m, now).apply) at_b.push_back(key(c.what));
  };
  for (int64_t seq : {5, 7, 8}) to_b(seq, 1100000);
  CHECK(at_b == std::vector<std::string>{"k4"});
  FleetExchange restarted = restart("a", w.data(), options());
  std::vector<std::string> adopted;
  int64_t now = 2000000;
  for (; restarted.fetching(); now += 100000) {
    const FetchRound round = fetch_round(restarted, {&b}, now);
    adopted.insert(adopted.end(), round.adopted.begin(), round.adopted.end());
    if (!restarted.fetching()) break;
  }
  CHECK(adopted == std::vector<std::string>{"k4", "?", "k6", "k7"});  // 7 and 8 at the wait's end, after 6's place
  CHECK(restarted.tail.counters().lost == 1);
  CHECK(restarted.outbox.next_seq("r1") == 9);
  // b asks the owner for 6: a placeholder that changes no graph, then b applies 7 and 8 as the owner did.
  for (const auto& request : b.due(now + 1000000).control) {
    if (request.kind != FleetControl::Kind::kRepair) continue;
    for (const auto& answer : restarted.received(request, now + 1000000).answers)
      for (const auto& c : b.received(answer, now + 1000000).apply) at_b.push_back(key(c.what));
  }
  CHECK(at_b == std::vector<std::string>{"k4", "?", "k6", "k7"});
  const Retained* copy = b.inbox.copy_of("r1", "a");
  REQUIRE(copy != nullptr);
  CHECK(copy->items.size() == 8);
  CHECK(std::get<slam::KeyframesThinned>(copy->items[5].what).keyframes == std::vector<int64_t>{INT64_MAX});
  CHECK(b.inbox.counters().owner_rewound == 0);
}

TEST_CASE("fleet exchange: a repair whose answers never reach the requester comes from a member holding a copy") {
  FleetExchange a("a", options()), b("b", options()), c("c", options());
  constexpr int64_t kCount = 200;                                                    // more than one message holds
  for (int64_t id = 0; id < kCount; ++id) CHECK(a.contributed(keyframe("r1", id)));  // numbers 1 to 200
  int64_t now = 1000000;
  size_t at_c = 0;
  for (const auto& m : a.due(now).contributions) at_c += c.received(m, now).apply.size();
  REQUIRE(at_c == kCount);
  // b gets 1 and 200 only: 2 to 199 are a gap it asks a for, and a's answers never reach it.
  std::vector<std::string> at_b, expected;
  for (int64_t id = 0; id < kCount; ++id) expected.push_back("k" + std::to_string(id));
  const auto to_b = [&](const FleetContributions& m) {
    for (const auto& got : b.received(m, now).apply) at_b.push_back(key(got.what));
  };
  for (int64_t seq : {int64_t{1}, kCount})
    to_b(FleetContributions{now, "a", "r1", false, seq, {keyframe("r1", seq - 1).what}});
  REQUIRE(at_b == std::vector<std::string>{"k0"});
  int asks = 0;
  for (; now < 5000000 && at_b.size() < expected.size(); now += 100000) {
    for (const auto& request : b.due(now).control) {
      if (request.kind != FleetControl::Kind::kRepair) continue;
      REQUIRE(request.daemon == "a");
      ++asks;
      CHECK_FALSE(a.received(request, now).answers.empty());  // the owner answers; the answers are lost
      const auto relays = c.received(request, now).answers;
      CHECK(relays.empty() == (asks < kRelayAfterAsks));  // c answers from its copy once b is seen stuck
      if (!relays.empty()) CHECK(relays.size() > 1);
      for (const auto& m : relays) {
        CHECK(m.sender == "c");
        CHECK(m.repair);
        to_b(m);  // every message of the relayed answer is taken, not only the first
      }
    }
  }
  CHECK(asks == kRelayAfterAsks);
  CHECK(at_b == expected);
  CHECK(b.inbox.counters().relays > 1);
  CHECK(c.outbox.counters().relayed == kCount - 2);
  CHECK(b.inbox.next_expected("r1") == kCount + 1);
  CHECK(b.inbox.owner("r1") == "a");  // the stream stays a's
}

TEST_CASE("fleet exchange: a member's repair of another's stream is taken only by a receiver stuck on that stream") {
  FleetExchange a("a", options()), b("b", options());
  for (int64_t id = 0; id < 3; ++id) CHECK(a.contributed(keyframe("r1", id)));
  int64_t now = 1000000;
  const auto from = [&](const std::string& sender, int64_t seq) {
    return FleetContributions{now, sender, "r1", true, seq, {keyframe("r1", seq - 1).what}};
  };
  CHECK(b.received(FleetContributions{now, "a", "r1", false, 1, {keyframe("r1", 0).what}}, now).apply.size() == 1);
  CHECK(b.received(FleetContributions{now, "a", "r1", false, 3, {keyframe("r1", 2).what}}, now).apply.empty());
  CHECK(b.received(from("c", 2), now).apply.empty());  // not stuck yet: overheard
  CHECK(b.inbox.counters().repairs_overheard == 1);
  for (int asks = 0; asks < kRelayAfterAsks; now += 100000)
    for (const auto& request : b.due(now).control) asks += request.kind == FleetControl::Kind::kRepair ? 1 : 0;
  CHECK(b.received(from("x", 2), now).apply.empty());  // not a member: refused, stuck or not
  CHECK(b.inbox.counters().not_member == 1);
  CHECK(b.received(from("c", 2), now).apply.size() == 2);  // stuck: a member's copy fills the gap, and 3 follows
  CHECK(b.inbox.counters().relays == 1);
  CHECK(b.received(from("c", 2), now).apply.empty());  // no longer stuck: overheard again
  CHECK(b.inbox.counters().repairs_overheard == 2);
}

TEST_CASE("fleet exchange: a repair that fills a later hole has the first gap asked for again without the back-off") {
  FleetExchange a("a", options()), b("b", options());
  for (int64_t id = 0; id < 6; ++id) CHECK(a.contributed(keyframe("r1", id)));  // numbers 1 to 6
  const int64_t start = 1000000;
  (void)a.due(start);  // sent, and lost on the way to b but for 1, 3, 4 and 6: holes at 2 and 5
  for (int64_t seq : {1, 3, 4, 6})
    (void)b.received(FleetContributions{start, "a", "r1", false, seq, {keyframe("r1", seq - 1).what}}, start);
  std::vector<int64_t> asked;
  for (int64_t t = start; t < start + 3000000 && asked.size() < 3; t += 10000)
    for (const auto& request : b.due(t).control) {
      if (request.kind != FleetControl::Kind::kRepair) continue;
      asked.push_back(t);
      for (const auto& answer : a.received(request, t).answers)  // the answer for 2 never arrives, 5's once
        if (asked.size() == 1 && answer.first == 5) CHECK(b.received(answer, t).apply.empty());
    }
  REQUIRE(asked.size() == 3);
  CHECK(asked[1] - asked[0] == 200000);  // a hole filled: the rest asked for again after repair_backoff_s
  CHECK(asked[2] - asked[1] == 400000);  // nothing since: backing off again
  CHECK(b.inbox.next_expected("r1") == 2);
}
