// Reading a fleet's estimate and ground truth (eval/fleet_log.hpp): the final trajectory per body rebuilt from UPDATE
// and SNAPSHOT messages, the chosen estimator's fused poses per body, the ground truth from GROUND_TRUTH messages
// and from files.
#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/lcm_log.hpp"
#include "eval/fleet_log.hpp"

#include <sextant/truth_t.hpp>

#include <doctest/doctest.h>

#include <cstdio>
#include <filesystem>

#include <unistd.h>

using namespace sextant;

namespace {

std::string temp(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("sextant_fleetlog_" + std::to_string(::getpid()) + "_" + name))
      .string();
}

engine::Pose at(double x, double y) {
  engine::Pose p;
  p.position = {x, y, 0};
  return p;
}

engine::Trajectory trajectory(const std::string& source, std::vector<engine::Keyframe> keyframes) {
  engine::Trajectory t;
  t.source = source;
  t.utime = keyframes.empty() ? 0 : keyframes.back().utime;
  t.keyframes = std::move(keyframes);
  t.total_keyframes = static_cast<int>(t.keyframes.size());
  return t;
}

}  // namespace

TEST_CASE("fleet log: final trajectories rebuilt per body, fused poses of one estimator, truth from messages") {
  const auto log = temp("out.lcm");
  {
    runtime::LogWriter w(log);
    int64_t seq = 0;
    w.write(
        1, "TRAJECTORY",
        runtime::to_message(trajectory("a", {{0, 1'000'000, at(0, 0)}, {1, 2'000'000, at(1, 0)}}), "sextantd", seq++));
    w.write(2, "TRAJECTORY", runtime::to_message(trajectory("b", {{0, 1'500'000, at(5, 5)}}), "sextantd", seq++));
    // A snapshot of a's ids 0..1 that carries only id 1 (moved): id 0 left the graph.
    auto snap = trajectory("a", {{1, 2'000'000, at(1, 0.5)}});
    snap.kind = engine::Trajectory::Kind::kSnapshot;
    snap.range_first = 0, snap.range_last = 1;
    w.write(3, "TRAJECTORY", runtime::to_message(snap, "sextantd", seq++));
    for (const char* estimator : {"graph", "ekf"}) {
      engine::FusedPose f;
      f.utime = 2'000'000, f.source = "a", f.estimator = estimator, f.pose = at(estimator[0] == 'g' ? 1 : 9, 0);
      w.write(4, estimator[0] == 'g' ? "FUSED_POSE" : "FUSED_POSE_EKF", runtime::to_message(f, "sextantd", seq++));
    }
    sextant::truth_t t{};
    t.kind = "robot", t.source = "b", t.utime = 1'500'000, t.position[0] = 3, t.orientation[0] = 1;
    w.write(5, "GROUND_TRUTH", t);
    t.kind = "landmark", t.source = "", t.id = 7, t.position[1] = 4;
    w.write(5, "GROUND_TRUTH", t);
  }
  const auto out = tools::read_fleet_output(log, "graph");
  REQUIRE(out.keyframes.size() == 2);
  REQUIRE(out.keyframes.at("a").size() == 1);
  CHECK(out.keyframes.at("a")[0].t == doctest::Approx(2.0));
  CHECK(out.keyframes.at("a")[0].pose.position.y() == 0.5);
  CHECK(out.keyframes.at("b")[0].pose.position.x() == 5);
  REQUIRE(out.fused.at("a").size() == 1);
  CHECK(out.fused.at("a")[0].pose.position.x() == 1);
  CHECK(tools::read_fleet_output(log, "ekf").fused.at("a")[0].pose.position.x() == 9);
  const auto truth = tools::read_truth_log(log);
  CHECK(truth.robots.at("b")[0].pose.position.x() == 3);
  CHECK(truth.landmarks.at(7).y() == 4);
  std::remove(log.c_str());
}

TEST_CASE("fleet log: ground truth files PREFIX BODY.txt and PREFIX landmarks.txt") {
  const auto prefix = temp("gt_");
  tools::write_tum(prefix + "robot1.txt", {{1.0, at(1, 2)}, {2.0, at(2, 2)}});
  tools::write_landmarks(prefix + "landmarks.txt", {{6, Eigen::Vector3d(1.5, -2.25, 0)}});
  const auto t = tools::read_truth_files(prefix, {"robot1", "robot2"});
  CHECK(t.robots.size() == 1);
  CHECK(t.robots.at("robot1").size() == 2);
  CHECK(t.landmarks.at(6).isApprox(Eigen::Vector3d(1.5, -2.25, 0)));
  // Spatial landmarks keep z; a malformed row is named.
  tools::write_landmarks(prefix + "landmarks.txt", {{6, Eigen::Vector3d(1, 2, 3)}}, false);
  CHECK(tools::read_landmarks(prefix + "landmarks.txt").at(6).z() == 3);
  std::FILE* f = std::fopen((prefix + "landmarks.txt").c_str(), "w");
  std::fputs("6 1 2\n6.5 1 2\n", f);
  std::fclose(f);
  CHECK_THROWS_WITH(tools::read_landmarks(prefix + "landmarks.txt"), doctest::Contains("landmarks.txt:2"));
  for (const char* n : {"robot1.txt", "landmarks.txt"}) std::remove((prefix + n).c_str());
}

TEST_CASE("fleet log: the last complete LANDMARK_MAP per frame, the frames bodies end in, logs merged") {
  const auto log = temp("maps.lcm");
  auto map = [](const std::string& frame, int chunk, int chunks, int total, std::vector<int64_t> ids) {
    engine::LandmarkMap m;
    m.frame = frame, m.chunk = chunk, m.num_chunks = chunks, m.total_landmarks = total;
    for (int64_t id : ids) m.landmarks.push_back({id, Eigen::Vector3d(static_cast<double>(id), 0, 0), 1});
    return m;
  };
  {
    runtime::LogWriter w(log);
    int64_t seq = 0;
    auto a = trajectory("a", {{0, 1'000'000, at(0, 0)}});
    auto b = trajectory("b", {{0, 1'000'000, at(0, 0)}});
    b.frame = "b";
    w.write(1, "TRAJECTORY", runtime::to_message(a, "sextantd", seq++));
    w.write(1, "TRAJECTORY", runtime::to_message(b, "sextantd", seq++));
    w.write(1, "LANDMARK_MAP", runtime::to_message(map("b", 0, 1, 1, {9}), "sextantd", seq++));
    w.write(2, "LANDMARK_MAP", runtime::to_message(map("a", 0, 2, 3, {1, 2}), "sextantd", seq++));
    w.write(2, "LANDMARK_MAP", runtime::to_message(map("a", 1, 2, 3, {3}), "sextantd", seq++));
    // A later publication of a's map replaces the earlier one; its first chunk alone is not complete yet.
    w.write(3, "LANDMARK_MAP", runtime::to_message(map("a", 0, 2, 2, {4}), "sextantd", seq++));
    // b joined a: b's frame is published once more, empty, and b's trajectory now names a.
    w.write(3, "LANDMARK_MAP", runtime::to_message(map("b", 0, 1, 0, {}), "sextantd", seq++));
    b.frame = "a";
    w.write(3, "TRAJECTORY", runtime::to_message(b, "sextantd", seq++));
  }
  auto out = tools::read_fleet_output(log, "graph");
  CHECK(out.frames.at("a") == "a");  // an unnamed frame is the body's own
  CHECK(out.frames.at("b") == "a");
  REQUIRE(out.maps.size() == 1);
  CHECK(out.maps.at("a").size() == 3);
  CHECK(out.maps.at("a").at(3).x() == 3);
  tools::FleetOutput other;
  other.keyframes["c"] = {{1.0, at(1, 1)}};
  other.maps["c"] = {{5, Eigen::Vector3d(5, 5, 0)}};
  tools::merge_into(out, std::move(other));
  CHECK(out.keyframes.size() == 3);
  CHECK(out.maps.size() == 2);
  std::remove(log.c_str());
}
