// Everything between the graphs of a fleet's daemons, end to end without the bus: three SlamGraphs, one per robot,
// each fed only its own robot's inputs, exchange their contributions through FleetExchange and the codec (the bytes
// of fleet_contribution_t and fleet_control_t) over a bus that loses, duplicates and reorders, with a cut of one
// daemon; each ends with the map one graph fed everything builds (the lead's scenario of
// tests/estimators/slam/test_slam_graph_contributions.cpp, there delivered in order by hand).
#include "daemon/engine/fleet_exchange.hpp"
#include "daemon/runtime/codec.hpp"
#include "estimators/slam/fleet_scenario.hpp"

#include <doctest/doctest.h>

#include <memory>
#include <random>

using namespace sextant;
using namespace sextant::slam;
using namespace sextant::slam::test;
using engine::FleetContributions;
using engine::FleetControl;

namespace {

/// A daemon: its graph, its exchange, and the listener that hands the graph's contributions to the exchange.
struct Daemon final : SlamListener {
  std::string name;
  engine::fleet::FleetExchange exchange;
  SlamGraph graph{three_robot_options()};
  Daemon(std::string n, const engine::FleetExchangeOptions& o) : name(n), exchange(n, o) {}
  void updated(const std::string&, int64_t, const graph::IncrementalStatus&) override {}
  void loop_proposed(const std::string&, int64_t, const KeyframeEstimate&, const KeyframeEstimate&, bool) override {}
  void contributed(const GraphContribution& c) override { CHECK(exchange.contributed(c)); }
  void apply(const engine::fleet::FleetExchange::Received& r, std::vector<std::vector<uint8_t>>& wire) {
    for (const auto& c : r.apply) graph.apply(c, *this);
    for (const auto& m : r.answers) wire.push_back(bytes(runtime::to_message(m, name, 0)));
  }
  template <class Msg>
  static std::vector<uint8_t> bytes(const Msg& m) {
    std::vector<uint8_t> b(static_cast<size_t>(m.getEncodedSize()));
    m.encode(b.data(), 0, static_cast<int>(b.size()));
    return b;
  }
};

/// What one daemon put on the bus in one step, as bytes: FLEET messages and FLEET_CONTROL messages.
struct Wire {
  std::vector<std::vector<uint8_t>> fleet, control;
};

// Delivers `from`'s bytes to every other daemon through the codec, each copy lost with `loss` (or all when `cut` is
// the sender or the receiver), some twice; answers to repair requests go on the bus in the next round.
void carry(std::vector<std::unique_ptr<Daemon>>& daemons, std::vector<Wire>& wires, std::mt19937& rng, double loss,
           int cut, int64_t now) {
  std::vector<Wire> next(daemons.size());
  std::uniform_real_distribution<double> u(0, 1);
  for (size_t from = 0; from < daemons.size(); ++from)
    for (size_t to = 0; to < daemons.size(); ++to) {
      if (to == from || static_cast<int>(to) == cut || static_cast<int>(from) == cut) continue;
      auto copies = wires[from].fleet;
      copies.insert(copies.end(), wires[from].control.begin(), wires[from].control.end());
      std::shuffle(copies.begin(), copies.end(), rng);
      for (const auto& b : copies) {
        if (u(rng) < loss) continue;
        for (int times = u(rng) < 0.1 ? 2 : 1; times > 0; --times) {
          auto d = runtime::decode_event(runtime::InputKind::kFleet, b.data(), b.size());
          if (std::holds_alternative<runtime::Rejection>(d))
            d = runtime::decode_event(runtime::InputKind::kFleetControl, b.data(), b.size());
          REQUIRE(std::holds_alternative<engine::Event>(d));
          std::visit(
              [&](const auto& e) {
                using T = std::decay_t<decltype(e)>;
                if constexpr (std::is_same_v<T, FleetContributions> || std::is_same_v<T, FleetControl>)
                  daemons[to]->apply(daemons[to]->exchange.received(e, now), next[to].fleet);
              },
              std::get<engine::Event>(d));
        }
      }
    }
  wires = std::move(next);
}

}  // namespace

TEST_CASE(
    "fleet exchange: three graphs, one per daemon, over a bus losing 30 % with one daemon cut off for a while, end "
    "with the map one graph fed everything builds") {
  const auto world = random_landmarks(3, 30);
  SlamGraph single(three_robot_options());
  Quiet quiet;
  engine::FleetExchangeOptions o;
  o.enabled = true;
  o.members = {"da", "db", "dc"};
  std::vector<std::unique_ptr<Daemon>> daemons;
  for (const auto& n : o.members) daemons.push_back(std::make_unique<Daemon>(n, o));
  std::vector<Wire> wires(3);
  std::mt19937 rng(11);
  int64_t now = 1000000;
  const auto round = [&](int cut) {
    for (size_t k = 0; k < daemons.size(); ++k) {
      auto due = daemons[k]->exchange.due(now);
      for (const auto& m : due.contributions)
        wires[k].fleet.push_back(Daemon::bytes(runtime::to_message(m, daemons[k]->name, 0)));
      for (const auto& m : due.control)
        wires[k].control.push_back(Daemon::bytes(runtime::to_message(m, daemons[k]->name, 0)));
    }
    carry(daemons, wires, rng, 0.3, cut, now);
  };
  for (int i = 0; i <= 200; ++i) {
    now += 100000;
    for (int k = 0; k < 3; ++k) {
      feed_three_robots(single, k, i, world, quiet);
      feed_three_robots(daemons[static_cast<size_t>(k)]->graph, k, i, world, *daemons[static_cast<size_t>(k)]);
    }
    round(i >= 80 && i < 140 ? 2 : -1);  // dc hears nothing and is heard by no one for 6 s
  }
  for (int i = 0; i < 300; ++i) {  // then only the exchange runs, until every stream is whole
    now += 100000;
    round(-1);
  }
  CHECK(single.frames().size() == 1);
  for (const auto& d : daemons) {
    CAPTURE(d->name);
    const auto& in = d->exchange.inbox.counters();
    CHECK(in.lost == 0);
    CHECK(in.repair_requests > 0);
    CHECK(d->exchange.inbox.held() == 0);
    CHECK(d->graph.frames().size() == 1);
    CHECK(d->graph.counters().fleet_contributions_refused == 0);
    CHECK(d->graph.counters().fleet_contributions_waiting == 0);
    for (const Robot& r : kThreeRobots) CHECK(rms_between(d->graph.keyframes(r.name), single.keyframes(r.name)) < 0.01);
    CHECK(d->graph.landmarks("a").size() == single.landmarks("a").size());
  }
}
