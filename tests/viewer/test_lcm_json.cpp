// The JSON form of sextant's messages: field by field as the .lcm file declares them, back to the same bytes, errors
// naming the field path, and a schema that lists exactly the fields the JSON carries.
#include "viewer/lcm_json.hpp"

#include <doctest/doctest.h>
#include <sextant/fused_pose_t.hpp>
#include <sextant/status_t.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <regex>

using namespace sextant::viewer;

namespace {

template <class Msg>
std::vector<uint8_t> encode(const Msg& m) {
  std::vector<uint8_t> b(static_cast<size_t>(m.getEncodedSize()));
  REQUIRE(m.encode(b.data(), 0, static_cast<int>(b.size())) == static_cast<int>(b.size()));
  return b;
}

sextant::fused_pose_t pose() {
  sextant::fused_pose_t m{};
  m.utime = 1700000000123456;
  m.sender = "sextantd";
  m.seq = 42;
  m.source = "robot1";
  m.estimator = "ekf";
  m.planar = 1;
  m.position[0] = 1.5, m.position[1] = -2.25, m.position[2] = 0.1;
  m.orientation[0] = 1;
  for (int i = 0; i < 36; ++i) m.covariance[i] = i % 7 == 0 ? 0.01 * (i + 1) : 0;
  m.lag_us = 250000;
  return m;
}

/// The field names a .lcm file declares, in order (its own reading, independent of the generator's).
std::vector<std::string> lcm_fields(const std::string& type) {
  std::ifstream in(std::string(SEXTANT_SOURCE_DIR) + "/lcmtypes/sextant/" + type + ".lcm");
  const std::string text{std::istreambuf_iterator<char>(in), {}};
  std::vector<std::string> out;
  const std::regex field(R"(\n\s*[a-z_0-9]+\s+([a-z_0-9]+)\s*(\[[a-z_0-9]+\])?\s*;)");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), field); it != std::sregex_iterator(); ++it)
    out.push_back((*it)[1]);
  return out;
}

}  // namespace

TEST_CASE("fused_pose_t: JSON field by field, and back to the same bytes") {
  const auto bytes = encode(pose());
  const auto* type = lcm_json_type_of(bytes.data(), bytes.size());
  REQUIRE(type != nullptr);
  CHECK(type->name == "sextant.fused_pose_t");
  const auto j = type->decode(bytes.data(), bytes.size(), nullptr);
  REQUIRE(j);
  CHECK((*j)["utime"] == 1700000000123456);
  CHECK((*j)["source"] == "robot1");
  CHECK((*j)["planar"] == true);
  CHECK((*j)["position"][1] == -2.25);
  CHECK((*j)["covariance"].size() == 36);
  CHECK((*j)["lag_us"] == 250000);
  CHECK(j->dump().find("\"utime\":1700000000123456,\"sender\":\"sextantd\"") !=
        std::string::npos);  // declaration order
  CHECK(type->encode(Json::parse(j->dump())) == bytes);
}

TEST_CASE("status_t: nested arrays with their counts, non-finite doubles survive as strings") {
  sextant::status_t s{};
  s.sender = "d";
  s.version = "v";
  s.num_stages = 2;
  s.stages.resize(2);
  s.stages[0].name = "graph";
  s.stages[0].latency_ms_p50 = std::numeric_limits<double>::quiet_NaN();
  s.stages[1].name = "ekf";
  s.stages[1].latency_ms_max = -std::numeric_limits<double>::infinity();
  s.stages[1].num_counters = 1;
  s.stages[1].counter_names = {"keyframes"};
  s.stages[1].counter_values = {7};
  const auto bytes = encode(s);
  const auto* type = lcm_json_type_named("sextant.status_t");
  REQUIRE(type);
  const auto j = type->decode(bytes.data(), bytes.size(), nullptr);
  REQUIRE(j);
  CHECK((*j)["stages"][0]["latency_ms_p50"] == "NaN");
  CHECK((*j)["stages"][1]["latency_ms_max"] == "-Infinity");
  CHECK((*j)["stages"][1]["counter_values"][0] == 7);
  CHECK(type->encode(Json::parse(j->dump())) == bytes);
}

TEST_CASE("JSON that is not a message is refused with the field path") {
  const auto* type = lcm_json_type_named("sextant.status_t");
  const auto bytes = encode(sextant::status_t{});
  Json j = *type->decode(bytes.data(), bytes.size(), nullptr);
  SUBCASE("an array longer than its count") {
    j["channels"] = Json::array({Json::object()});
    CHECK_THROWS_WITH(type->encode(j), "status_t.channels: has 1 elements, its size says 0");
  }
  SUBCASE("a nested field of the wrong type") {
    j["num_stages"] = 1;
    sextant::stage_status_t st{};
    Json stage = Json::object();
    j["stages"] = Json::array({stage});
    CHECK_THROWS_WITH(type->encode(j), "status_t.stages[0].name: missing");
  }
  SUBCASE("an integer out of its field's range") {
    j["num_channels"] = int64_t{1} << 40;
    CHECK_THROWS_WITH(type->encode(j), "status_t.num_channels: integer out of range");
  }
  SUBCASE("a string with a NUL character, which an LCM string cannot hold") {
    j["sender"] = std::string("sextant\0d", 9);
    CHECK_THROWS_WITH(type->encode(j), "status_t.sender: holds a NUL character (\\u0000)");
  }
  SUBCASE("a string for a number") {
    j["uptime_s"] = "fast";
    CHECK_THROWS_WITH(type->encode(j), "status_t.uptime_s: expected a number");
  }
}

TEST_CASE("bytes that are not the type are refused, not half-decoded") {
  auto bytes = encode(pose());
  bytes.resize(bytes.size() - 5);
  std::string error;
  CHECK_FALSE(lcm_json_type_named("sextant.fused_pose_t")->decode(bytes.data(), bytes.size(), &error));
  CHECK(!error.empty());
  const std::vector<uint8_t> junk(20, 0xAB);
  CHECK(lcm_json_type_of(junk.data(), junk.size()) == nullptr);
}

TEST_CASE("every type's schema lists exactly the fields its .lcm file declares, in order, all required") {
  size_t lcm_files = 0;  // one type per .lcm file, none left out
  for (const auto& f : std::filesystem::directory_iterator(std::string(SEXTANT_SOURCE_DIR) + "/lcmtypes/sextant"))
    lcm_files += f.path().extension() == ".lcm";
  CHECK(lcm_json_types().size() == lcm_files);
  for (const auto& t : lcm_json_types()) {
    CAPTURE(t.name);
    const Json schema = Json::parse(t.schema);
    CHECK(schema["title"] == t.name);
    CHECK(schema["type"] == "object");
    std::vector<std::string> props;
    for (const auto& [k, v] : schema["properties"].items()) props.push_back(k);
    CHECK(props == lcm_fields(t.name.substr(8)));
    CHECK(schema["required"].get<std::vector<std::string>>() == props);
  }
  const Json fp = Json::parse(lcm_json_type_named("sextant.fused_pose_t")->schema);
  CHECK(fp["properties"]["covariance"]["minItems"] == 36);
  CHECK(fp["properties"]["planar"]["type"] == "boolean");
  CHECK(fp["properties"]["source"]["description"] == "the body");
}
