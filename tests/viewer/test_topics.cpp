// The mapping to Foxglove topics: a fused pose as PoseInFrame and frame transforms, a trajectory rebuilt as a line,
// a target's covariance as its 95 % ellipsoid, bytes without a JSON form kept raw or dropped.
#include "viewer/topics.hpp"

#include <doctest/doctest.h>
#include <sextant/fused_pose_t.hpp>
#include <sextant/geo_pose_t.hpp>
#include <sextant/targets_t.hpp>
#include <sextant/trajectory_t.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <utility>

using namespace sextant::viewer;

namespace {

template <class Msg>
std::vector<ViewerMessage> map(TopicMapper& mapper, const std::string& channel, const Msg& m) {
  std::vector<uint8_t> b(static_cast<size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  std::vector<ViewerMessage> out;
  mapper.map(channel, b.data(), b.size(), out);
  return out;
}

const ViewerMessage& on(const std::vector<ViewerMessage>& v, const std::string& topic) {
  for (const auto& m : v)
    if (m.topic == topic) return m;
  FAIL("no message on " << topic);
  return v.front();
}

sextant::fused_pose_t pose(const std::string& estimator, double x) {
  sextant::fused_pose_t m{};
  m.utime = 12'500'000;
  m.source = "robot1";
  m.estimator = estimator;
  m.position[0] = x, m.position[1] = 2, m.position[2] = 3;
  const double h = std::sqrt(0.5);
  m.orientation[0] = h, m.orientation[3] = h;  // 90 degrees about z
  return m;
}

}  // namespace

TEST_CASE("a fused pose: its as-is topic, a PoseInFrame and the frames map -> source/estimator and map -> source") {
  TopicMapper mapper;
  const auto out = map(mapper, "FUSED_POSE", pose("ekf", 1));
  REQUIRE(out.size() == 3);
  CHECK(out[0].topic == "FUSED_POSE");
  CHECK(out[0].schema->name == "sextant.fused_pose_t");
  CHECK(out[0].lcm_channel == "FUSED_POSE");
  const Json p = Json::parse(on(out, "/sextant/robot1/ekf/pose").data);
  CHECK(on(out, "/sextant/robot1/ekf/pose").schema->name == "foxglove.PoseInFrame");
  CHECK(p["timestamp"]["sec"] == 12);
  CHECK(p["timestamp"]["nsec"] == 500'000'000);
  CHECK(p["frame_id"] == "map");
  CHECK(p["pose"]["position"]["x"] == 1.0);
  CHECK(p["pose"]["orientation"]["w"].get<double>() == doctest::Approx(std::sqrt(0.5)));
  CHECK(p["pose"]["orientation"]["z"].get<double>() == doctest::Approx(std::sqrt(0.5)));
  const Json tf = Json::parse(on(out, "/tf").data);
  REQUIRE(tf["transforms"].size() == 2);
  CHECK(tf["transforms"][0]["child_frame_id"] == "robot1/ekf");
  CHECK(tf["transforms"][1]["child_frame_id"] == "robot1");

  // A worse estimator of the same body gets its own frame but does not move the body's.
  const Json tf2 = Json::parse(on(map(mapper, "FUSED_POSE", pose("dead_reckoning", 9)), "/tf").data);
  CHECK(tf2["transforms"].size() == 1);
  CHECK(tf2["transforms"][0]["child_frame_id"] == "robot1/dead_reckoning");
}

TEST_CASE("a pose on the Earth: its as-is topic and a LocationFix for the Map panel, with its ENU covariance") {
  TopicMapper mapper;
  sextant::geo_pose_t g{};
  g.utime = 3'250'000;
  g.source = "husky";
  g.estimator = "inertial";
  g.heading_known = true;
  g.latitude = 40.5, g.longitude = -73.25, g.altitude = 12.5;
  g.orientation[0] = 1;
  for (int i = 0; i < 9; ++i) g.position_covariance[i] = i % 4 == 0 ? 0.25 * (1 + i / 4) : 0.01;
  const auto out = map(mapper, "FUSED_GEO", g);
  REQUIRE(out.size() == 2);
  CHECK(out[0].schema->name == "sextant.geo_pose_t");
  const ViewerMessage& fix = on(out, "/sextant/husky/inertial/fix");
  CHECK(fix.schema->name == "foxglove.LocationFix");
  const Json j = Json::parse(fix.data);
  CHECK(j["timestamp"]["sec"] == 3);
  CHECK(j["timestamp"]["nsec"] == 250'000'000);
  CHECK(j["latitude"] == 40.5);
  CHECK(j["longitude"] == -73.25);
  CHECK(j["altitude"] == 12.5);
  REQUIRE(j["position_covariance"].size() == 9);
  for (int i = 0; i < 9; ++i) CHECK(j["position_covariance"][i].get<double>() == g.position_covariance[i]);
  CHECK(j["position_covariance_type"] == 3);
}

namespace {

sextant::trajectory_t trajectory_update(const std::vector<int64_t>& ids, double y) {
  sextant::trajectory_t t{};
  t.source = "robot1";
  t.estimator = "graph";
  t.kind = sextant::trajectory_t::UPDATE;
  for (int64_t id : ids) {
    sextant::keyframe_t k{};
    k.id = id;
    k.position[0] = static_cast<double>(id);
    k.position[1] = y;
    k.orientation[0] = 1;
    t.keyframes.push_back(k);
  }
  t.num_keyframes = static_cast<int32_t>(t.keyframes.size());
  return t;
}

/// The strips of one SceneUpdate by entity id, each as its points' x (= keyframe id) and y.
std::map<std::string, std::vector<std::pair<double, double>>> strips(const Json& update) {
  std::map<std::string, std::vector<std::pair<double, double>>> out;
  for (const auto& e : update["entities"]) {
    auto& pts = out[e["id"].get<std::string>()];
    for (const auto& l : e["lines"])
      for (const auto& p : l["points"]) pts.emplace_back(p["x"].get<double>(), p["y"].get<double>());
  }
  return out;
}

}  // namespace

TEST_CASE(
    "trajectory messages rebuild each body's trajectory as trajectory_t.lcm says, redrawing the segments they touch") {
  TopicMapper mapper;
  std::vector<int64_t> ids(600);
  for (int64_t i = 0; i < 600; ++i) ids[static_cast<size_t>(i)] = i;
  const auto first =
      strips(Json::parse(on(map(mapper, "TRAJECTORY", trajectory_update(ids, 0)), "/sextant/trajectories").data));
  // 600 keyframes: segments [0,256), [256,512), [512,600), each strip joined to the previous one's last keyframe.
  REQUIRE(first.count("robot1/trajectory/0"));
  CHECK(first.at("robot1/trajectory/0").size() == 256);
  CHECK(first.at("robot1/trajectory/1").size() == 257);
  CHECK(first.at("robot1/trajectory/1").front().first == 255.0);
  CHECK(first.at("robot1/trajectory/2").size() == 89);
  CHECK(first.at("robot1/trajectory/2").back().first == 599.0);

  // A snapshot chunk for ids [300, 310] carrying only 305 (moved): 300..310 but 305 are erased, and only segment 1
  // (and the one after it, whose strip starts at segment 1's end) is redrawn.
  auto snapshot = trajectory_update({305}, 7);
  snapshot.kind = sextant::trajectory_t::SNAPSHOT;
  snapshot.range_first = 300, snapshot.range_last = 310;
  const auto second = strips(Json::parse(on(map(mapper, "TRAJECTORY", snapshot), "/sextant/trajectories").data));
  CHECK_FALSE(second.count("robot1/trajectory/0"));
  REQUIRE(second.count("robot1/trajectory/1"));
  const auto& seg = second.at("robot1/trajectory/1");
  CHECK(seg.size() == 257 - 10);
  CHECK(std::count(seg.begin(), seg.end(), std::make_pair(305.0, 7.0)) == 1);
  CHECK(std::none_of(seg.begin(), seg.end(),
                     [](const auto& p) { return p.first >= 300 && p.first <= 310 && p.first != 305; }));
  CHECK(second.count("robot1/trajectory/label"));

  // An open-ended snapshot range (to the largest id) erases the keyframes from its start on, quickly.
  auto tail = trajectory_update({}, 0);
  tail.kind = sextant::trajectory_t::SNAPSHOT;
  tail.range_first = 590, tail.range_last = std::numeric_limits<int64_t>::max();
  const auto third = strips(Json::parse(on(map(mapper, "TRAJECTORY", tail), "/sextant/trajectories").data));
  REQUIRE(third.count("robot1/trajectory/2"));
  CHECK(third.at("robot1/trajectory/2").back().first == 589.0);
  CHECK(third.size() == 3);  // segments 2 and 3, and the label
}

TEST_CASE("a target's ellipsoid has the 95 % diameters of its covariance along its principal axes") {
  TopicMapper mapper;
  sextant::targets_t m{};
  sextant::target_t target{};
  target.position[0] = 10;
  target.covariance[0] = 4.0, target.covariance[4] = 1.0, target.covariance[8] = 0.25;  // sigma 2, 1, 0.5 m
  m.targets = {target};
  m.num_targets = 1;
  const Json u = Json::parse(on(map(mapper, "TARGETS", m), "/sextant/targets").data);
  const auto& size = u["entities"][0]["spheres"][0]["size"];
  std::vector<double> d = {size["x"], size["y"], size["z"]};
  std::sort(d.begin(), d.end());
  const double k = 2 * std::sqrt(7.814727903251178);  // chi-square, 3 degrees of freedom, 95 %
  CHECK(d[0] == doctest::Approx(k * 0.5));
  CHECK(d[1] == doctest::Approx(k * 1.0));
  CHECK(d[2] == doctest::Approx(k * 2.0));
}

TEST_CASE("bytes without a JSON form: kept raw for files, dropped by the bridge, counted") {
  const std::vector<uint8_t> junk(40, 0x5A);
  std::vector<ViewerMessage> out;
  TopicMapper file({true, true});
  file.map("MYSTERY", junk.data(), junk.size(), out);
  REQUIRE(out.size() == 1);
  CHECK(out[0].topic == "lcm_raw/MYSTERY");
  CHECK(out[0].encoding == "lcm");
  CHECK(out[0].schema == nullptr);
  CHECK(out[0].data == std::string(junk.begin(), junk.end()));
  out.clear();
  TopicMapper bridge;
  bridge.map("MYSTERY", junk.data(), junk.size(), out);
  CHECK(out.empty());
  CHECK(bridge.counts().raw == 1);
}

TEST_CASE("batched frame transforms: every pose's transforms, in order, in one /tf message at flush") {
  TopicMapperOptions options;
  options.batch_frame_transforms = true;
  TopicMapper mapper(options);
  auto first = map(mapper, "FUSED_POSE", pose("ekf", 1));
  auto second = map(mapper, "FUSED_POSE", pose("dead_reckoning", 2));
  CHECK(std::none_of(first.begin(), first.end(), [](const ViewerMessage& m) { return m.topic == "/tf"; }));
  CHECK(std::none_of(second.begin(), second.end(), [](const ViewerMessage& m) { return m.topic == "/tf"; }));
  std::vector<ViewerMessage> flushed;
  mapper.flush(flushed);
  REQUIRE(flushed.size() == 1);
  const Json tf = Json::parse(on(flushed, "/tf").data);
  REQUIRE(tf["transforms"].size() == 3);
  CHECK(tf["transforms"][0]["child_frame_id"] == "robot1/ekf");
  CHECK(tf["transforms"][1]["child_frame_id"] == "robot1");
  CHECK(tf["transforms"][2]["child_frame_id"] == "robot1/dead_reckoning");
  CHECK(tf["transforms"][2]["translation"]["x"] == 2.0);
  flushed.clear();
  mapper.flush(flushed);
  CHECK(flushed.empty());  // nothing gathered since
}

TEST_CASE("a pose in a fleet frame: PoseInFrame in <frame>/map, which hangs from map once per /tf message") {
  TopicMapperOptions options;
  options.batch_frame_transforms = true;
  TopicMapper mapper(options);
  auto ekf = pose("ekf", 1), dead_reckoning = pose("dead_reckoning", 2);
  ekf.frame = dead_reckoning.frame = "robot1";
  const auto out = map(mapper, "FUSED_POSE", ekf);
  CHECK(Json::parse(on(out, "/sextant/robot1/ekf/pose").data)["frame_id"] == "robot1/map");
  map(mapper, "FUSED_POSE", dead_reckoning);
  std::vector<ViewerMessage> flushed;
  mapper.flush(flushed);
  const Json tf = Json::parse(on(flushed, "/tf").data);
  std::vector<std::pair<std::string, std::string>> edges;
  for (const auto& t : tf["transforms"]) edges.emplace_back(t["parent_frame_id"], t["child_frame_id"]);
  CHECK(edges == std::vector<std::pair<std::string, std::string>>{{"map", "robot1/map"},
                                                                  {"robot1/map", "robot1/ekf"},
                                                                  {"robot1/map", "robot1"},
                                                                  {"robot1/map", "robot1/dead_reckoning"}});
  CHECK(tf["transforms"][0]["translation"] == Json{{"x", 0.0}, {"y", 0.0}, {"z", 0.0}});
  CHECK(tf["transforms"][0]["rotation"]["w"] == 1.0);
}
