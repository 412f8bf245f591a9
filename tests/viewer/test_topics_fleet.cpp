// The mapping to Foxglove topics for a fleet: a simulated three-robot run replayed through the engine and its outputs
// mapped as the bridge and the MCAP files map them.  Every pose is drawn in the map frame its message names, /tf
// connects every frame to the root "map" after each message, each LANDMARK_MAP publication is the scene of its frame
// (as many spheres as landmarks, at their positions), and the frame list says which frames are unplaced.  Then a
// chunked landmark map assembled whatever the order its chunks arrive in.
#include "viewer/topics.hpp"
#include "replay/replay_driver.hpp"
#include "sim/simulator.hpp"
#include "temp_path.hpp"

#include <doctest/doctest.h>
#include <sextant/fused_pose_t.hpp>
#include <sextant/landmark_map_t.hpp>
#include <sextant/trajectory_t.hpp>

#include <cstdio>
#include <map>
#include <set>

using namespace sextant;
using sextant::viewer::Json;
using sextant::viewer::TopicMapper;
using sextant::viewer::TopicMapperOptions;
using sextant::viewer::ViewerMessage;

namespace {

/// The entities of one SceneUpdate topic as a viewer holds them: deletions, then entities replaced by id.
struct Scene {
  std::map<std::string, Json> entities;
  void apply(const Json& update) {
    for (const auto& d : update["deletions"]) {
      if (d["type"] == 1)
        entities.clear();
      else
        entities.erase(d["id"].get<std::string>());
    }
    for (const auto& e : update["entities"]) entities[e["id"].get<std::string>()] = e;
  }
};

/// What a viewer holds after a sequence of viewer messages: each frame's parent (/tf), each SceneUpdate topic's
/// scene, the frames every message was drawn in.
struct Viewer {
  std::map<std::string, std::string> parent;
  std::map<std::string, Scene> scenes;
  std::map<std::string, Json> last;  // by topic
  std::set<std::string> drawn_in;    // frame ids of the poses and entities since the last check

  void receive(const ViewerMessage& m) {
    const Json j = Json::parse(m.data);
    last[m.topic] = j;
    if (m.topic == "/tf")
      for (const auto& t : j["transforms"]) parent[t["child_frame_id"]] = t["parent_frame_id"];
    if (m.schema && m.schema->name == "foxglove.PoseInFrame") drawn_in.insert(j["frame_id"].get<std::string>());
    if (m.schema && m.schema->name == "foxglove.SceneUpdate") {
      scenes[m.topic].apply(j);
      for (const auto& e : j["entities"]) drawn_in.insert(e["frame_id"].get<std::string>());
    }
  }
  /// The frames from `frame` up to the root, or empty when it has no path to "map" (or a cycle).
  std::vector<std::string> path(std::string frame) const {
    std::vector<std::string> out{frame};
    while (frame != "map") {
      const auto p = parent.find(frame);
      if (p == parent.end() || out.size() > parent.size() + 1) return {};
      out.push_back(frame = p->second);
    }
    return out;
  }
};

struct FleetOutputs {
  tools::SimulationSummary truth;
  std::vector<tools::PublishedMessage> published;
};

FleetOutputs replay_fleet() {
  const auto log = sextant::viewer::test::temp_path("fleet.lcm");
  tools::SimulationOptions o;
  o.robots = 3;
  o.duration_s = 90;
  o.seed = 5;
  FleetOutputs run;
  {
    runtime::LogWriter w(log);
    run.truth = tools::simulate(o, w);
    w.flush();
  }
  config::DaemonConfig cfg;
  cfg.engine.graph.fleet.markers = run.truth.markers;
  tools::ReplayOptions ro;
  ro.max_kept = 0;  // every published message
  run.published = tools::replay_log(log, cfg, {}, ro).published;
  std::remove(log.c_str());
  return run;
}

/// One replay for every test case of this file.
const FleetOutputs& fleet_run() {
  static const FleetOutputs run = replay_fleet();
  return run;
}

template <class Msg>
Msg decode(const tools::PublishedMessage& p) {
  Msg m;
  REQUIRE(m.decode(p.bytes.data(), 0, static_cast<int>(p.bytes.size())) == static_cast<int>(p.bytes.size()));
  return m;
}

std::string map_frame(const std::string& frame) { return frame.empty() ? "map" : frame + "/map"; }

/// The landmarks of a map frame's scene by label (the landmark id) -> sphere position.
std::map<std::string, std::array<double, 3>> scene_landmarks(const Scene& scene, const std::string& frame) {
  std::map<std::string, std::array<double, 3>> out;
  for (const auto& [id, e] : scene.entities) {
    if (id.rfind("landmark_map/" + frame + "/", 0) != 0) continue;
    CHECK(e["frame_id"] == map_frame(frame));
    REQUIRE(e["spheres"].size() == e["texts"].size());
    for (size_t i = 0; i < e["spheres"].size(); ++i) {
      const auto& p = e["spheres"][i]["pose"]["position"];
      out[e["texts"][i]["text"].get<std::string>()] = {p["x"].get<double>(), p["y"].get<double>(),
                                                       p["z"].get<double>()};
    }
  }
  return out;
}

/// Checks a landmark map publication (all its chunks) against the viewer's scene of its frame.
void check_landmark_map(const Viewer& v, const std::vector<sextant::landmark_map_t>& chunks) {
  const std::string& frame = chunks.front().frame;
  std::map<std::string, std::array<double, 3>> want;
  for (const auto& c : chunks)
    for (const auto& l : c.landmarks) want[std::to_string(l.id)] = {l.position[0], l.position[1], l.position[2]};
  CAPTURE(frame);
  CHECK(static_cast<int>(want.size()) == chunks.front().total_landmarks);
  const auto scene = v.scenes.count("/sextant/landmark_map")
                         ? scene_landmarks(v.scenes.at("/sextant/landmark_map"), frame)
                         : std::map<std::string, std::array<double, 3>>{};
  CHECK(scene == want);
}

}  // namespace

TEST_CASE("a fleet's outputs: each body under its map frame, every frame connected to map, the landmark maps") {
  const FleetOutputs& run = fleet_run();
  TopicMapper mapper;
  Viewer v;
  int64_t poses = 0, maps = 0, joined_maps = 0;
  std::map<std::pair<std::string, int64_t>, std::vector<sextant::landmark_map_t>> publications;  // (frame, utime)
  std::map<std::string, std::set<std::string>> graph_frames;  // body -> the frames its graph poses were in
  std::map<std::string, std::string> trajectory_frame;        // body -> its latest trajectory's frame
  for (const auto& p : run.published) {
    std::vector<ViewerMessage> out;
    mapper.map(p.channel, p.bytes.data(), p.bytes.size(), out);
    REQUIRE_FALSE(out.empty());
    CHECK(out[0].topic == p.channel);  // the as-is channel first, as for every sextant channel
    for (const auto& m : out) v.receive(m);
    for (const auto& f : v.drawn_in) {  // every frame drawn in has a path to the display frame
      CAPTURE(f);
      CHECK_FALSE(v.path(f).empty());
    }
    v.drawn_in.clear();
    if (p.channel.rfind("FUSED_POSE", 0) == 0) {
      const auto m = decode<sextant::fused_pose_t>(p);
      const Json& pose = v.last.at("/sextant/" + m.source + "/" + m.estimator + "/pose");
      CHECK(pose["frame_id"] == map_frame(m.frame));
      CHECK(pose["pose"]["position"]["x"].get<double>() == m.position[0]);
      CHECK(pose["pose"]["position"]["y"].get<double>() == m.position[1]);
      CHECK(v.parent.at(m.source + "/" + m.estimator) == map_frame(m.frame));
      if (m.estimator == "graph") {
        graph_frames[m.source].insert(m.frame);
        CHECK(v.parent.at(m.source) == map_frame(m.frame));  // the body's frame follows its best estimator
      }
      ++poses;
    } else if (p.channel == "TRAJECTORY") {
      trajectory_frame[decode<sextant::trajectory_t>(p).source] = decode<sextant::trajectory_t>(p).frame;
    } else if (p.channel == "LANDMARK_MAP") {
      const auto m = decode<sextant::landmark_map_t>(p);
      auto& chunks = publications[{m.frame, m.utime}];
      chunks.push_back(m);
      if (static_cast<int>(chunks.size()) == m.num_chunks) {
        check_landmark_map(v, chunks);
        ++maps;
        joined_maps += m.total_landmarks == 0;
      }
    }
  }
  CHECK(poses > 3 * 3 * 4000);  // three robots, three estimators, 50 Hz for 90 s
  CHECK(maps > 80);         // robot1's frame at the trajectory's rate (1 Hz) for 90 s, the others' before they joined
  CHECK(joined_maps == 2);  // robot2's and robot3's own maps, once each when they joined robot1's
  // The graph placed each robot in its own frame first and in robot1's at the end (robot3 may pass through robot2's,
  // when those two join first).
  CHECK(graph_frames["robot1"] == std::set<std::string>{"robot1"});
  CHECK(graph_frames["robot2"] == std::set<std::string>{"robot1", "robot2"});
  CHECK(graph_frames["robot3"].contains("robot3"));
  CHECK(graph_frames["robot3"].contains("robot1"));
  CHECK(graph_frames["robot3"].size() <= 3);
  for (const auto& [body, frame] : trajectory_frame) {
    CAPTURE(body);
    CHECK(frame == "robot1");
    CHECK(v.parent.at(body) == "robot1/map");
    CHECK(v.parent.at(body + "/ekf") == body + "/map");  // the filters stay in the body's own frame
    CHECK(v.path(body + "/ekf").size() == 3);            // robotN/ekf -> robotN/map -> map
    for (const auto& [id, e] : v.scenes.at("/sextant/trajectories").entities)
      if (id.rfind(body + "/", 0) == 0) CHECK(e["frame_id"] == "robot1/map");
  }
  // Only robot1's map is left, with every landmark the robots saw.
  const auto& scene = v.scenes.at("/sextant/landmark_map");
  CHECK(scene_landmarks(scene, "robot2").empty());
  CHECK(scene_landmarks(scene, "robot3").empty());
  CHECK(scene_landmarks(scene, "robot1").size() > 30);
  // The frame list: robot1's frame is the display frame, the filters' frames of the others are not placed in it.
  const std::string frames = v.last.at("/sextant/frames")["entities"][0]["texts"][0]["text"];
  CHECK(frames ==
        "robot1/map = map (robot1, robot2, robot3)\n"
        "robot2/map unplaced: drawn at map's origin (robot2)\n"
        "robot3/map unplaced: drawn at map's origin (robot3)");
}

TEST_CASE("a fleet through the bridge's batched frame transforms: after each batch every frame drawn in reaches map") {
  TopicMapperOptions options;
  options.batch_frame_transforms = true;
  TopicMapper mapper(options);
  Viewer v;
  size_t batches = 0, placements = 0;  // placements: map -> <frame>/map
  const auto& published = fleet_run().published;
  for (size_t i = 0; i < published.size(); ++i) {
    std::vector<ViewerMessage> out;
    mapper.map(published[i].channel, published[i].bytes.data(), published[i].bytes.size(), out);
    if (i % 64 == 63 || i + 1 == published.size()) {  // the bridge flushes after each batch it maps together
      mapper.flush(out);
      ++batches;
    }
    for (const auto& m : out) {
      v.receive(m);
      if (m.topic != "/tf") continue;
      const Json tf = Json::parse(m.data);
      for (const auto& t : tf["transforms"]) placements += t["parent_frame_id"] == "map";
    }
    if (i % 64 != 63) continue;
    for (const auto& f : v.drawn_in) {
      CAPTURE(f);
      CHECK_FALSE(v.path(f).empty());
    }
    v.drawn_in.clear();
  }
  CHECK(batches == (published.size() + 63) / 64);
  CHECK(v.path("robot2") == std::vector<std::string>{"robot2", "robot1/map", "map"});
  CHECK(v.path("robot3/dead_reckoning") == std::vector<std::string>{"robot3/dead_reckoning", "robot3/map", "map"});
  // Each map frame placed once per batch, not once per pose: three frames at most, in every batch (each has poses).
  CHECK(placements >= batches);
  CHECK(placements <= 3 * batches);
}

namespace {

sextant::landmark_map_t map_chunk(int64_t utime, int32_t chunk, int32_t num_chunks, int32_t total, int64_t first_id,
                                  int32_t n) {
  sextant::landmark_map_t m{};
  m.utime = utime;
  m.sender = "sextantd";
  m.frame = "robot1";
  m.bodies = {"robot1"};
  m.num_bodies = 1;
  m.chunk = chunk;
  m.num_chunks = num_chunks;
  m.total_landmarks = total;
  for (int64_t id = first_id; id < first_id + n; ++id) {
    sextant::map_landmark_t l{};
    l.id = id;
    l.position[0] = static_cast<double>(id);
    l.position[1] = -0.5 * static_cast<double>(id);
    l.sightings = 2;
    m.landmarks.push_back(l);
  }
  m.num_landmarks = n;
  return m;
}

std::vector<ViewerMessage> map(TopicMapper& mapper, const sextant::landmark_map_t& m) {
  std::vector<uint8_t> b(static_cast<size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  std::vector<ViewerMessage> out;
  mapper.map("LANDMARK_MAP", b.data(), b.size(), out);
  return out;
}

/// Maps the messages into `v`; how many /sextant/landmark_map updates they gave.
int feed(TopicMapper& mapper, Viewer& v, const std::vector<sextant::landmark_map_t>& messages) {
  int updates = 0;
  for (const auto& m : messages)
    for (const auto& out : map(mapper, m)) {
      v.receive(out);
      updates += out.topic == "/sextant/landmark_map";
    }
  return updates;
}

}  // namespace

TEST_CASE("a chunked landmark map is drawn once all its chunks are there, whatever their order, and replaced whole") {
  TopicMapper mapper;
  Viewer v;
  // 2500 landmarks in chunks of 1024: ids 0..1023, 1024..2047, 2048..2499; chunk 2 first, chunk 1 twice.
  const auto c0 = map_chunk(1'000'000, 0, 3, 2500, 0, 1024), c1 = map_chunk(1'000'000, 1, 3, 2500, 1024, 1024),
             c2 = map_chunk(1'000'000, 2, 3, 2500, 2048, 452);
  CHECK(feed(mapper, v, {c2, c1, c1}) == 0);  // incomplete: nothing drawn yet
  CHECK(feed(mapper, v, {c0}) == 1);
  check_landmark_map(v, {c0, c1, c2});
  CHECK(v.path("robot1/map") == std::vector<std::string>{"robot1/map", "map"});
  CHECK(feed(mapper, v, {c1}) == 0);  // a repeat of a chunk of the drawn map

  // A newer map of 1500 landmarks: its first chunk alone draws nothing; a late chunk of the older publication is
  // ignored; once complete, it replaces the old map (the third group of 1024 deleted).
  const auto d0 = map_chunk(2'000'000, 0, 2, 1500, 10'000, 1024), d1 = map_chunk(2'000'000, 1, 2, 1500, 11'024, 476);
  CHECK(feed(mapper, v, {d0, c2}) == 0);
  check_landmark_map(v, {c0, c1, c2});  // still the old one
  CHECK(feed(mapper, v, {d1}) == 1);
  check_landmark_map(v, {d0, d1});
  CHECK(v.scenes.at("/sextant/landmark_map").entities.size() == 2);

  // A publication whose chunk 1 was lost is never drawn: the next one replaces it.
  const auto e0 = map_chunk(3'000'000, 0, 2, 1100, 0, 1024);
  const auto f0 = map_chunk(4'000'000, 0, 1, 7, 500, 7);
  CHECK(feed(mapper, v, {e0, f0}) == 1);
  check_landmark_map(v, {f0});

  // The frame joined another: a map of no landmarks deletes its spheres.
  CHECK(feed(mapper, v, {map_chunk(5'000'000, 0, 1, 0, 0, 0)}) == 1);
  CHECK(v.scenes.at("/sextant/landmark_map").entities.empty());

  // A chunk index out of range is an error of the view (the as-is message still goes out).
  const auto bad = map(mapper, map_chunk(6'000'000, 3, 2, 10, 0, 1));
  REQUIRE(bad.size() == 1);
  CHECK(bad[0].topic == "LANDMARK_MAP");
  CHECK(mapper.counts().view_errors == 1);
}
