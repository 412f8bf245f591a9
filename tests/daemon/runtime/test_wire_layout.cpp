// The wire layouts against lcm-gen's encoder, and the decoders under lengths and counts that do not fit: every input
// type refuses them with the field named, and nothing throws (lcm-gen 1.3.1's decode threw std::length_error on a
// zero-length string and resized arrays to whatever count the bytes claimed).
#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/wire_layout.hpp"

#include "daemon/runtime/encode_message.hpp"

#include <doctest/doctest.h>
#include <sextant/status_t.hpp>
#include <sextant/targets_t.hpp>
#include <sextant/trajectory_t.hpp>

#include <random>
#include <string>
#include <vector>

using namespace sextant;
using runtime::Decoded;
using runtime::InputKind;
using runtime::Rejection;

namespace {

std::string random_string(std::mt19937& rng) {
  std::uniform_int_distribution<int> len(0, 12), ch('a', 'z');
  std::string s(static_cast<size_t>(len(rng)), ' ');
  for (char& c : s) c = static_cast<char>(ch(rng));
  return s;
}

template <size_t N>
void fill(double (&a)[N], std::mt19937& rng) {
  std::normal_distribution<double> d;
  for (double& x : a) x = d(rng);
}

sextant::odometry_t random_odometry(std::mt19937& rng) {
  sextant::odometry_t m{};
  m.utime = static_cast<int64_t>(rng());
  m.sender = random_string(rng);
  m.seq = rng();
  m.source = random_string(rng);
  m.planar = rng() % 2;
  fill(m.position, rng), fill(m.orientation, rng), fill(m.covariance, rng), fill(m.increment_covariance, rng);
  fill(m.linear_velocity, rng), fill(m.angular_velocity, rng), fill(m.twist_covariance, rng);
  return m;
}

sextant::landmarks_t random_landmarks(std::mt19937& rng) {
  sextant::landmarks_t m{};
  m.utime = 5;
  m.sender = random_string(rng);
  m.source = random_string(rng);
  fill(m.sensor_position, rng), fill(m.sensor_orientation, rng);
  m.num_observations = static_cast<int32_t>(rng() % 5);
  for (int i = 0; i < m.num_observations; ++i) {
    sextant::landmark_observation_t o{};
    o.id = static_cast<int64_t>(rng());
    fill(o.covariance, rng);
    m.observations.push_back(o);
  }
  return m;
}

sextant::bearing_scan_t random_scan(std::mt19937& rng) {
  sextant::bearing_scan_t m{};
  m.utime = 7;
  m.sender = random_string(rng);
  m.sensor_id = static_cast<int32_t>(rng() % 100);
  fill(m.sensor_position, rng);
  m.num_detections = static_cast<int32_t>(rng() % 5);
  for (int i = 0; i < m.num_detections; ++i) m.detections.push_back({0.1 * i, 0.2, 0.01, 0.02});
  return m;
}

sextant::loop_closure_t random_loop(std::mt19937& rng) {
  sextant::loop_closure_t m{};
  m.utime = 9;
  m.sender = random_string(rng);
  m.source = random_string(rng);
  m.matcher = random_string(rng);
  fill(m.position, rng), fill(m.orientation, rng), fill(m.information, rng);
  return m;
}

sextant::truth_t random_truth(std::mt19937& rng) {
  sextant::truth_t m{};
  m.sender = random_string(rng), m.kind = random_string(rng), m.source = random_string(rng);
  return m;
}

sextant::match_request_t random_request(std::mt19937& rng) {
  sextant::match_request_t m{};
  m.sender = random_string(rng), m.source = random_string(rng), m.kind = random_string(rng);
  return m;
}

sextant::fused_pose_t random_fused(std::mt19937& rng) {
  sextant::fused_pose_t m{};
  m.sender = random_string(rng), m.source = random_string(rng), m.estimator = random_string(rng);
  return m;
}

sextant::geo_pose_t random_geo(std::mt19937& rng) {
  sextant::geo_pose_t m{};
  m.sender = random_string(rng), m.source = random_string(rng), m.estimator = random_string(rng);
  m.heading_known = rng() % 2 == 0, m.latitude = 45.0, m.position_covariance[8] = 2.0;
  return m;
}

sextant::status_t random_status(std::mt19937& rng) {
  sextant::status_t m{};
  m.utime = static_cast<int64_t>(rng()), m.sender = random_string(rng), m.seq = rng(), m.version = random_string(rng);
  m.num_channels = static_cast<int32_t>(rng() % 3);
  for (int i = 0; i < m.num_channels; ++i) {
    sextant::channel_status_t c{};
    c.channel = random_string(rng), c.last_error = random_string(rng), c.lost = rng();
    c.num_reasons = static_cast<int32_t>(rng() % 3);
    for (int k = 0; k < c.num_reasons; ++k) c.reasons.push_back(random_string(rng)), c.reason_counts.push_back(rng());
    m.channels.push_back(c);
  }
  m.num_stages = static_cast<int32_t>(rng() % 3);
  for (int i = 0; i < m.num_stages; ++i) {
    sextant::stage_status_t st{};
    st.name = random_string(rng), st.last_failure = random_string(rng);
    st.num_counters = static_cast<int32_t>(rng() % 4);
    for (int k = 0; k < st.num_counters; ++k)
      st.counter_names.push_back(random_string(rng)), st.counter_values.push_back(rng());
    m.stages.push_back(st);
  }
  m.num_outputs = static_cast<int32_t>(rng() % 4);
  for (int k = 0; k < m.num_outputs; ++k) {
    m.output_channels.push_back(random_string(rng));
    m.output_counts.push_back(rng()), m.output_bytes.push_back(rng()), m.output_bytes_per_s.push_back(rng() * 0.5);
  }
  return m;
}

sextant::trajectory_t random_trajectory(std::mt19937& rng) {
  sextant::trajectory_t m{};
  m.sender = random_string(rng), m.source = random_string(rng), m.estimator = random_string(rng);
  m.kind = static_cast<int8_t>(rng() % 2), m.chunk = 3, m.total_keyframes = 9;
  m.num_keyframes = static_cast<int32_t>(rng() % 4);
  for (int i = 0; i < m.num_keyframes; ++i) {
    sextant::keyframe_t k{};
    k.id = i;
    fill(k.position, rng), fill(k.orientation, rng);
    m.keyframes.push_back(k);
  }
  m.num_removed = static_cast<int32_t>(rng() % 3);
  for (int i = 0; i < m.num_removed; ++i) m.removed_ids.push_back(rng());
  return m;
}

sextant::targets_t random_targets(std::mt19937& rng) {
  sextant::targets_t m{};
  m.sender = random_string(rng), m.cost_kind = random_string(rng);
  m.num_sensors = static_cast<int32_t>(rng() % 4);
  for (int i = 0; i < m.num_sensors; ++i) m.sensor_ids.push_back(static_cast<int32_t>(rng() % 10));
  m.num_targets = static_cast<int32_t>(rng() % 4);
  for (int i = 0; i < m.num_targets; ++i) {
    sextant::target_t t{};
    fill(t.position, rng), fill(t.covariance, rng);
    t.num_sensors = m.num_sensors;
    t.detection_indices.assign(static_cast<size_t>(m.num_sensors), -1);
    m.targets.push_back(t);
  }
  return m;
}

// The layout accepts the whole encoding and refuses every proper prefix of it: it ends exactly where lcm-gen's
// encoding ends, field by field (a field the layout missed or invented would shift the end).
template <class Msg>
void check_layout_matches(const Msg& m) {
  const auto b = encode(m);
  const auto& layout = runtime::wire_layout<Msg>();
  CHECK_FALSE(runtime::wire_error(layout, b.data(), b.size()).has_value());
  for (size_t n = 8; n < b.size(); ++n)
    if (!runtime::wire_error(layout, b.data(), n))
      FAIL_CHECK(layout.type << ": a prefix of " << n << " of " << b.size() << " bytes passed");
}

std::vector<uint8_t> with_i32_at(std::vector<uint8_t> b, size_t at, int32_t v) {
  const auto u = static_cast<uint32_t>(v);
  b[at] = static_cast<uint8_t>(u >> 24), b[at + 1] = static_cast<uint8_t>(u >> 16);
  b[at + 2] = static_cast<uint8_t>(u >> 8), b[at + 3] = static_cast<uint8_t>(u);
  return b;
}

Rejection rejection(const Decoded& d) {
  REQUIRE(std::holds_alternative<Rejection>(d));
  return std::get<Rejection>(d);
}

}  // namespace

TEST_CASE("wire layouts end where lcm-gen's encodings end, for random messages of every type") {
  std::mt19937 rng(3);
  for (int k = 0; k < 40; ++k) {
    check_layout_matches(random_odometry(rng));
    check_layout_matches(random_landmarks(rng));
    check_layout_matches(random_scan(rng));
    check_layout_matches(random_loop(rng));
    check_layout_matches(random_truth(rng));
    check_layout_matches(random_request(rng));
    check_layout_matches(random_fused(rng));
    check_layout_matches(random_geo(rng));
    check_layout_matches(random_status(rng));
    check_layout_matches(random_trajectory(rng));
    check_layout_matches(random_targets(rng));
  }
}

TEST_CASE("a zero-length string is refused with the field named, for every input type (lcm-gen threw length_error)") {
  // The 20-byte odometry payload: fingerprint, utime, then a sender length of 0.
  std::vector<uint8_t> b(20, 0);
  int64_t hash = sextant::odometry_t::getHash();
  __int64_t_encode_array(b.data(), 0, 8, &hash, 1);
  b[15] = 1;  // utime 1
  Decoded d;
  CHECK_NOTHROW(d = runtime::decode_event(InputKind::kOdometry, b.data(), b.size()));
  auto r = rejection(d);
  CHECK(r.reason == "decode");
  CHECK(r.message.find("odometry_t.sender: string length 0") != std::string::npos);

  std::mt19937 rng(1);
  // The source string of landmarks (after utime, sender "x", seq), the sender of a scan and of a loop closure.
  auto lm = random_landmarks(rng);
  lm.sender = "x";
  const auto lb = with_i32_at(encode(lm), 8 + 8 + 4 + 2 + 8, 0);
  CHECK_NOTHROW(d = runtime::decode_event(InputKind::kLandmarks, lb.data(), lb.size()));
  CHECK(rejection(d).message.find("landmarks_t.source: string length 0") != std::string::npos);
  const auto sb = with_i32_at(encode(random_scan(rng)), 16, 0);
  CHECK_NOTHROW(d = runtime::decode_event(InputKind::kBearings, sb.data(), sb.size()));
  CHECK(rejection(d).message.find("bearing_scan_t.sender: string length 0") != std::string::npos);
  const auto cb = with_i32_at(encode(random_loop(rng)), 16, -5);
  CHECK_NOTHROW(d = runtime::decode_event(InputKind::kLoopClosures, cb.data(), cb.size()));
  CHECK(rejection(d).message.find("loop_closure_t.sender: string length -5") != std::string::npos);
}

TEST_CASE("array counts beyond the bytes or the maximum are refused before anything is allocated") {
  std::mt19937 rng(2);
  auto lm = random_landmarks(rng);
  lm.sender = "s", lm.source = "r";
  lm.num_observations = 0, lm.observations.clear();
  auto b = encode(lm);
  const size_t count_at = b.size() - 4;
  for (int32_t n : {0x7fffffff, 20'000'000}) {
    const auto big = with_i32_at(b, count_at, n);
    const auto r = rejection(runtime::decode_event(InputKind::kLandmarks, big.data(), big.size()));
    CHECK(r.reason == "too_large");
    CHECK(r.message.find("landmarks_t.num_observations: " + std::to_string(n)) != std::string::npos);
  }
  // Within the maximum but more than the bytes hold: 100 observations claimed, none sent.
  const auto r =
      rejection(runtime::decode_event(InputKind::kLandmarks, with_i32_at(b, count_at, 100).data(), b.size()));
  CHECK(r.reason == "decode");
  CHECK(r.message.find("landmarks_t.observations: 100 elements") != std::string::npos);
  const auto neg = with_i32_at(b, count_at, -1);
  CHECK(rejection(runtime::decode_event(InputKind::kLandmarks, neg.data(), neg.size())).reason == "decode");

  auto scan = random_scan(rng);
  scan.num_detections = 0, scan.detections.clear();
  auto sb = encode(scan);
  const auto big = with_i32_at(sb, sb.size() - 4, 0x7fffffff);
  const auto rs = rejection(runtime::decode_event(InputKind::kBearings, big.data(), big.size()));
  CHECK(rs.reason == "too_large");
  CHECK(rs.message.find("bearing_scan_t.num_detections") != std::string::npos);
}

TEST_CASE("a string without its NUL and an array cut short are refused, naming the field") {
  std::mt19937 rng(4);
  auto lm = random_landmarks(rng);
  lm.sender = "abc";
  auto b = encode(lm);
  b[8 + 8 + 4 + 3] = 'x';  // the NUL of "abc"
  CHECK(
      rejection(runtime::decode_event(InputKind::kLandmarks, b.data(), b.size())).message.find("does not end in NUL") !=
      std::string::npos);
  lm = random_landmarks(rng);
  lm.num_observations = 2;
  lm.observations.resize(2);
  const auto full = encode(lm);
  const auto r = rejection(runtime::decode_event(InputKind::kLandmarks, full.data(), full.size() - 10));
  CHECK(r.message.find("landmarks_t.observations: 2 elements of at least 104 bytes exceed the 198 bytes left") !=
        std::string::npos);
}

TEST_CASE("decoding mutated messages of every input type never throws") {
  // A small deterministic fuzz next to the libFuzzer harness (tests/fuzz/): valid encodings with random bytes
  // overwritten, inserted or cut, including length and count fields.
  std::mt19937 rng(5);
  const std::vector<std::pair<InputKind, std::vector<uint8_t>>> seeds{
      {InputKind::kOdometry, encode(random_odometry(rng))},
      {InputKind::kLandmarks, encode(random_landmarks(rng))},
      {InputKind::kBearings, encode(random_scan(rng))},
      {InputKind::kLoopClosures, encode(random_loop(rng))}};
  int refused = 0, total = 0;
  for (int k = 0; k < 20000; ++k) {
    const auto& [kind, seed] = seeds[static_cast<size_t>(k) % seeds.size()];
    auto b = seed;
    const int edits = 1 + static_cast<int>(rng() % 4);
    for (int e = 0; e < edits; ++e) {
      const size_t at = 8 + rng() % (b.size() - 8);
      switch (rng() % 4) {
        case 0:
          b[at] = static_cast<uint8_t>(rng());
          break;
        case 1:
          b[at] = (rng() % 2) ? 0xff : 0x00;
          break;
        case 2:
          b.resize(at);
          break;
        default:
          b.insert(b.begin() + static_cast<std::ptrdiff_t>(at), static_cast<uint8_t>(rng()));
      }
      if (b.size() <= 8) b = seed;
    }
    Decoded d;
    CHECK_NOTHROW(d = runtime::decode_event(kind, b.data(), b.size()));
    refused += std::holds_alternative<Rejection>(d) ? 1 : 0;
    ++total;
  }
  CHECK(refused > total / 4);  // the mutations do reach the checks
}

TEST_CASE("the outputs as tools read them: a count the bytes cannot hold is refused before anything is allocated") {
  std::mt19937 rng(6);
  auto t = random_trajectory(rng);
  t.num_removed = 0, t.removed_ids.clear();
  const auto tb = encode(t);
  sextant::trajectory_t tout;
  for (int32_t n : {0x7fffffff, 20'000'000}) {
    const auto big = with_i32_at(tb, tb.size() - 4, n);
    std::optional<runtime::WireError> e;
    CHECK_NOTHROW(e = runtime::safe_decode(big.data(), big.size(), tout));
    REQUIRE(e.has_value());
    CHECK(e->message.find("trajectory_t.") == 0);
  }
  // A status whose outputs count claims more than its four parallel arrays hold.
  sextant::status_t s{};
  s.sender = "d", s.version = "v";
  s.num_outputs = 1;
  s.output_channels = {"POSE"}, s.output_counts = {1}, s.output_bytes = {2}, s.output_bytes_per_s = {3};
  const auto sb = encode(s);
  // From the end: output_bytes_per_s, output_bytes, output_counts (8 bytes each), "POSE" (4 + 5), num_outputs.
  const size_t num_outputs_at = sb.size() - (8 + 8 + 8 + 4 + 5 + 4);
  CHECK(sb[num_outputs_at + 3] == 1);
  const auto claimed = with_i32_at(sb, num_outputs_at, 2);  // num_outputs: 1 -> 2
  sextant::status_t sout;
  std::optional<runtime::WireError> e;
  CHECK_NOTHROW(e = runtime::safe_decode(claimed.data(), claimed.size(), sout));
  REQUIRE(e.has_value());
  CHECK(e->message.find("status_t.output_channels[1]") != std::string::npos);
  CHECK_FALSE(runtime::safe_decode(sb.data(), sb.size(), sout).has_value());
  CHECK(sout.output_bytes_per_s.at(0) == 3.0);
}

TEST_CASE("safe_decode of an output type refuses a zero-length string and catches what lcm-gen throws") {
  sextant::status_t s{};
  s.sender = "x";
  auto b = encode(s);
  b[8 + 8 + 3] = 0;  // the sender's length -> 0
  sextant::status_t out;
  std::optional<runtime::WireError> e;
  CHECK_NOTHROW(e = runtime::safe_decode(b.data(), b.size(), out));
  REQUIRE(e.has_value());
  CHECK(e->reason == "decode");
}
