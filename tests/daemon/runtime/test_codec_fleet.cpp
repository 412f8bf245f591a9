// The fleet's messages at the codec and the intake (daemon/runtime/codec_fleet.cpp): every kind of contribution goes
// to the wire and back to the same bytes, the exchange's size accounting is lcm-gen's encoded size, every bad value is
// refused naming its field, bytes that do not fit are refused without throwing, and the intake counts both.
#include "daemon/engine/fleet_exchange.hpp"
#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/encode_message.hpp"
#include "daemon/runtime/intake.hpp"
#include "daemon/runtime/wire_layout.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <limits>

using namespace sextant;
using engine::FleetContributions;
using engine::FleetControl;
using runtime::InputKind;

namespace {

slam::KeyframeAnchor anchor(int64_t keyframe) {
  slam::KeyframeAnchor a;
  a.keyframe = keyframe;
  a.motion = SE3(Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ())), Eigen::Vector3d(0.5, 0.1, 0));
  a.covariance = Matrix6d::Identity() * 1e-3;
  return a;
}

slam::LandmarkSighting sighting(int64_t id) {
  slam::LandmarkSighting s;
  s.id = id;
  s.range = 2.5;
  s.azimuth = 0.4;
  s.covariance = Eigen::Vector3d(0.01, 0.001, 0).asDiagonal();
  return s;
}

// One contribution of every kind (and a first keyframe, and a big sightings message).
std::vector<engine::fleet::What> every_kind() {
  slam::KeyframeContribution first;
  first.id = 0, first.utime = 10, first.first = true, first.planar = true;
  first.odom_covariance = Matrix6d::Identity() * 1e-4;
  slam::KeyframeContribution k = first;
  k.id = 1, k.utime = 20, k.first = false, k.reanchored = true;
  k.edge = anchor(0).motion;
  k.edge_covariance = Matrix6d::Identity() * 1e-2;
  slam::SightingsContribution s;
  s.anchor = anchor(1);
  s.sightings.utime = 21;
  s.sightings.planar = true;
  for (int i = 0; i < 256; ++i) s.sightings.sightings.push_back(sighting(i));
  const slam::BodySightingHalf half{"robot2", 22, SE3(), sighting(2), anchor(1)};
  const slam::BodySighting whole{"robot3", 23, SE3(), sighting(1), anchor(4), anchor(1)};
  const slam::LoopContribution loop{0, 1, anchor(0).motion, Matrix6d::Identity() * 100, true};
  slam::BodyLoopHalf loop_half;
  loop_half.loop.utime_from = 30, loop_half.loop.utime_to = 31, loop_half.loop.body_to = "robot2";
  loop_half.loop.relative = anchor(0).motion;
  loop_half.from = anchor(1);
  const slam::BodyLoop body_loop{"robot2", 7, 1, anchor(0).motion, Matrix6d::Identity() * 50};
  const slam::FrameJoin join{"robot0", anchor(2).motion};
  const slam::KeyframesThinned thinned{{3, 4, 9}};
  return {first, k, s, half, whole, loop, loop_half, body_loop, join, thinned};
}

FleetContributions batch() {
  FleetContributions c;
  c.utime = 100;
  c.sender = "alpha";
  c.body = "robot1";
  c.first = 7;
  c.contributions = every_kind();
  return c;
}

std::string rejection(const runtime::Decoded& d) {
  const auto* r = std::get_if<runtime::Rejection>(&d);
  return r ? r->reason + ": " + r->message : std::string("accepted");
}

template <class Msg>
runtime::Decoded decode(InputKind kind, const Msg& m) {
  const auto b = encode(m);
  return runtime::decode_event(kind, b.data(), b.size());
}

}  // namespace

TEST_CASE("fleet codec: every kind of contribution goes to the wire and back to the same bytes") {
  const auto m = runtime::to_message(batch(), "alpha", 3);
  const auto bytes = encode(m);
  runtime::MessageOrigin origin;
  const auto d = runtime::decode_event(InputKind::kFleet, bytes.data(), bytes.size(), &origin);
  REQUIRE(rejection(d) == "accepted");
  CHECK(origin.sender == "alpha");
  CHECK(origin.seq == 3);
  const auto& e = std::get<FleetContributions>(std::get<engine::Event>(d));
  CHECK(e.first == 7);
  CHECK(e.body == "robot1");
  REQUIRE(e.contributions.size() == 10);
  CHECK(std::get<slam::KeyframesThinned>(e.contributions[9]).keyframes == std::vector<int64_t>{3, 4, 9});
  CHECK(std::get<slam::FrameJoin>(e.contributions[8]).keep == "robot0");
  CHECK(std::get<slam::KeyframeContribution>(e.contributions[1]).reanchored);
  CHECK(std::get<slam::LoopContribution>(e.contributions[5]).widened);
  CHECK(std::get<slam::BodyLoopHalf>(e.contributions[6]).loop.body_to == "robot2");
  CHECK(encode(runtime::to_message(e, "alpha", 3)) == bytes);

  const FleetControl hb{5, "alpha", FleetControl::Kind::kHeartbeat, "", {{"robot1", 1, 9}, {"robot4", 0, 0}}};
  const auto cb = encode(runtime::to_message(hb, "alpha", 1));
  const auto dc = runtime::decode_event(InputKind::kFleetControl, cb.data(), cb.size());
  REQUIRE(rejection(dc) == "accepted");
  CHECK(encode(runtime::to_message(std::get<FleetControl>(std::get<engine::Event>(dc)), "alpha", 1)) == cb);
}

TEST_CASE("fleet codec: the exchange's size of an item and of a message is lcm-gen's encoded size") {
  const auto b = batch();
  size_t total = engine::fleet::message_overhead_bytes("alpha", b.body);
  for (const auto& w : b.contributions) {
    CHECK(engine::fleet::item_bytes(w) == static_cast<size_t>(runtime::to_item(w)._getEncodedSizeNoHash()));
    total += engine::fleet::item_bytes(w);
  }
  CHECK(total == static_cast<size_t>(runtime::to_message(b, "alpha", 0).getEncodedSize()));
  CHECK(total < 60000);
  // The Outbox's messages are under max_message_bytes on the wire.
  engine::FleetExchangeOptions o;
  o.members = {"alpha"};
  engine::fleet::Outbox out("alpha", o);
  for (int i = 0; i < 50; ++i)
    for (const auto& w : every_kind()) out.add({"robot1", w});
  for (const auto& m : out.take_messages(1)) CHECK(runtime::to_message(m, "alpha", 0).getEncodedSize() <= 60000);
}

TEST_CASE("fleet codec: each bad value is refused naming its field") {
  const auto base = runtime::to_message(batch(), "alpha", 0);
  const auto refused = [&](auto change) {
    auto m = base;
    change(m);
    return rejection(decode(InputKind::kFleet, m));
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  CHECK(refused([&](auto& m) { m.contributions[2].anchors[0].covariance[7] = nan; }) ==
        "non_finite: fleet_contribution_t.contributions[2].anchors[0].covariance[7]: not finite (nan)");
  CHECK(
      refused([](auto& m) {
        m.contributions[1].poses[1].matrix[0] = -1;
      }).starts_with("covariance: fleet_contribution_t.contributions[1].poses[1].matrix: not positive semi-definite"));
  CHECK(refused([](auto& m) { m.contributions[1].poses[1].matrix[1] = 0.5; }) ==
        "covariance: fleet_contribution_t.contributions[1].poses[1].matrix: not symmetric");
  CHECK(refused([](auto& m) {
          m.contributions[0].poses[0].orientation[0] = 2;
        }).starts_with("quaternion: fleet_contribution_t.contributions[0].poses[0].orientation"));
  CHECK(refused([](auto& m) { m.contributions[3].kind = 10; }) ==
        "invalid: fleet_contribution_t.contributions[3].kind: unknown (10)");
  CHECK(refused([](auto& m) {
          m.contributions[5].flags = sextant::fleet_item_t::FIRST;
        }).starts_with("invalid: fleet_contribution_t.contributions[5].flags"));
  CHECK(refused([](auto& m) {
          m.contributions[4].anchors.pop_back();
          m.contributions[4].num_anchors = 1;
        }).starts_with("invalid: fleet_contribution_t.contributions[4].num_anchors: 1, its kind has 2"));
  CHECK(refused([](auto& m) { m.contributions[2].sightings[3].range = -1; }) ==
        "invalid: fleet_contribution_t.contributions[2].sightings[3].range: not positive");
  CHECK(refused([](auto& m) {
          m.contributions[2].sightings[0].id = -1;
        }).starts_with("invalid: fleet_contribution_t.contributions[2].sightings[0].id"));
  CHECK(refused([](auto& m) { m.contributions[3].other = std::string("rob\x01t"); }) ==
        "invalid: fleet_contribution_t.contributions[3].other: a control character");
  CHECK(refused([](auto& m) {
          m.contributions[0].other = "robot9";
        }).starts_with("invalid: fleet_contribution_t.contributions[0].other"));
  CHECK(refused([](auto& m) { m.contributions[8].other = ""; }) ==
        "invalid: fleet_contribution_t.contributions[8].other: empty");
  CHECK(refused([](auto& m) {
          m.contributions[8].anchors.push_back(m.contributions[2].anchors[0]);
          m.contributions[8].num_anchors = 1;
        }).starts_with("invalid: fleet_contribution_t.contributions[8].num_anchors: 1, its kind has 0"));
  CHECK(refused([](auto& m) { m.contributions[9].keyframes[1] = -4; }) ==
        "invalid: fleet_contribution_t.contributions[9].keyframes[1]: negative keyframe id");
  CHECK(refused([](auto& m) {
          m.contributions[9].keyframes.clear();
          m.contributions[9].num_keyframes = 0;
        }) == "invalid: fleet_contribution_t.contributions[9].num_keyframes: 0 outside [1, 1024]");
  CHECK(refused([](auto& m) {
          m.contributions[0].keyframes = {1};
          m.contributions[0].num_keyframes = 1;
        }) == "invalid: fleet_contribution_t.contributions[0].num_keyframes: 1 outside [0, 0]");
  CHECK(refused([](auto& m) { m.body = std::string(300, 'b'); }) ==
        "invalid: fleet_contribution_t.body: longer than 256 characters");
  CHECK(refused([](auto& m) { m.sender = ""; }) == "invalid: fleet_contribution_t.sender: empty");
  CHECK(refused([](auto& m) { m.first = 0; }).starts_with("invalid: fleet_contribution_t.first"));
  CHECK(refused([](auto& m) {
          m.first = std::numeric_limits<int64_t>::max();
        }).starts_with("invalid: fleet_contribution_t.first"));
  CHECK(refused([](auto& m) {
          m.contributions.clear();
          m.num_contributions = 0;
        }).starts_with("too_large: fleet_contribution_t.num_contributions"));
  CHECK(refused([](auto& m) { m.contributions[0].utime = 0; }) ==
        "invalid: fleet_contribution_t.contributions[0].utime: not positive (0)");

  const FleetControl request{5, "beta", FleetControl::Kind::kRepair, "alpha", {{"robot1", 1, 9}}};
  const auto cbase = runtime::to_message(request, "beta", 0);
  const auto crefused = [&](auto change) {
    auto m = cbase;
    change(m);
    return rejection(decode(InputKind::kFleetControl, m));
  };
  CHECK(crefused([](auto&) {}) == "accepted");
  CHECK(crefused([](auto& m) { m.streams[0].first = 0; }).starts_with("invalid: fleet_control_t.streams[0]: range"));
  CHECK(crefused([](auto& m) { m.streams[0].last = 0; }).starts_with("invalid: fleet_control_t.streams[0]: range"));
  CHECK(crefused([](auto& m) { m.daemon = ""; }) == "invalid: fleet_control_t.daemon: empty");
  CHECK(crefused([](auto& m) { m.kind = sextant::fleet_control_t::HEARTBEAT; }) ==
        "invalid: fleet_control_t.daemon: set on a heartbeat");
  CHECK(crefused([](auto& m) { m.kind = 3; }) == "invalid: fleet_control_t.kind: unknown (3)");
}

TEST_CASE("fleet codec: the owner's check of a contribution is the decoder's, naming the field") {
  for (const auto& what : every_kind()) CHECK(runtime::fleet_item_error(what).empty());
  // The stream-stopping value of a restart that anchored waiting sightings by a negative interpolation.
  slam::SightingsContribution s;
  s.anchor = anchor(3);
  s.anchor.covariance(0, 0) = -2.3e-6;
  s.sightings.utime = 21;
  s.sightings.sightings.push_back(sighting(0));
  const std::string why = runtime::fleet_item_error(s);
  CHECK(why.find("fleet_item_t.anchors[0].covariance: not positive semi-definite") != std::string::npos);
  CHECK(why.rfind("covariance: ", 0) == 0);  // the decoder's reason first
  slam::KeyframeContribution k = std::get<slam::KeyframeContribution>(every_kind()[1]);
  k.edge_covariance(2, 2) = std::numeric_limits<double>::quiet_NaN();
  CHECK(runtime::fleet_item_error(k).rfind("non_finite: ", 0) == 0);
  // The same contribution in a received message is refused for the same reason.
  FleetContributions m = batch();
  m.contributions = {s};
  const std::string refused = rejection(decode(InputKind::kFleet, runtime::to_message(m, "a", 1)));
  REQUIRE(refused.find("anchors[0]") != std::string::npos);
  CHECK(refused.substr(refused.find("anchors[0]")) == why.substr(why.find("anchors[0]")));
}

TEST_CASE("fleet codec: bytes that do not fit are refused before anything is allocated, never thrown") {
  const auto bytes = encode(runtime::to_message(batch(), "alpha", 0));
  for (size_t n = 0; n < bytes.size(); n += 7) {
    runtime::Decoded d;
    CHECK_NOTHROW(d = runtime::decode_event(InputKind::kFleet, bytes.data(), n));
    CHECK(std::holds_alternative<runtime::Rejection>(d));
  }
  // A count claiming more contributions than the codec takes: refused by the layout walk, naming the field.
  auto big = bytes;
  const size_t at = 8 + 8 + (4 + 6) + 8 + (4 + 7) + 1 + 8;  // num_contributions
  big[at] = 0x7f;
  const auto r = rejection(runtime::decode_event(InputKind::kFleet, big.data(), big.size()));
  CHECK(r.starts_with("too_large: fleet_contribution_t.num_contributions"));
  const std::vector<uint8_t> junk(300, 0xAB);
  CHECK(
      rejection(runtime::decode_event(InputKind::kFleetControl, junk.data(), junk.size())).starts_with("fingerprint"));
}

TEST_CASE(
    "fleet codec: the intake takes FLEET and FLEET_CONTROL without the sensors' clock checks, counting refusals") {
  runtime::ChannelStats stats;
  runtime::Intake intake(stats);
  intake.add_channel("FLEET", InputKind::kFleet);
  intake.add_channel("FLEET_CONTROL", InputKind::kFleetControl);
  const auto good = encode(runtime::to_message(batch(), "alpha", 0));
  // Old sender clocks, the same times again: the exchange orders by sequence number, not by time.
  for (int i = 0; i < 3; ++i)
    CHECK(intake.accept("FLEET", good.data(), good.size(), runtime::Arrival::at_log_time(1)).has_value());
  auto bad_message = runtime::to_message(batch(), "alpha", 3);
  bad_message.contributions[0].poses[0].position[1] = std::numeric_limits<double>::infinity();
  const auto bad = encode(bad_message);
  CHECK_FALSE(intake.accept("FLEET", bad.data(), bad.size(), runtime::Arrival::at_log_time(2)).has_value());
  const std::vector<uint8_t> junk(40, 1);
  CHECK_FALSE(intake.accept("FLEET_CONTROL", junk.data(), junk.size(), runtime::Arrival::at_log_time(2)).has_value());
  const auto counts = stats.snapshot();
  CHECK(counts.at("FLEET").decoded == 3);
  CHECK(counts.at("FLEET").rejected == 1);
  CHECK(counts.at("FLEET").reasons.at("non_finite") == 1);
  CHECK(counts.at("FLEET_CONTROL").rejected == 1);
}
