// The bridge's own WebSocket framing read by Beast's client: messages of every length encoding (7-bit, 16-bit and
// 64-bit), text and binary, arrive whole and in order, many of them written together.
#include "viewer/batched_write_stream.hpp"
#include "viewer/foxglove_bridge.hpp"

#include <doctest/doctest.h>
#include <sextant/trajectory_t.hpp>

#include <boost/asio/connect.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>

#include <chrono>
#include <thread>

using namespace sextant::viewer;
namespace net = boost::asio;
namespace beast = boost::beast;
namespace websocket = beast::websocket;

namespace {

/// A trajectory whose JSON form grows with `keyframes` (about 150 bytes each).
std::vector<uint8_t> trajectory(int64_t seq, int keyframes) {
  sextant::trajectory_t m{};
  m.utime = 1'000'000 + seq;
  m.sender = "test";
  m.seq = seq;
  m.source = "robot1";
  m.estimator = "graph";
  m.kind = sextant::trajectory_t::UPDATE;
  m.num_keyframes = keyframes;
  for (int i = 0; i < keyframes; ++i) {
    sextant::keyframe_t k{};
    k.id = i;
    k.utime = i;
    k.position[0] = i;
    k.orientation[0] = 1;
    m.keyframes.push_back(k);
  }
  std::vector<uint8_t> b(static_cast<size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

struct Client {
  net::io_context io;
  websocket::stream<net::ip::tcp::socket> ws{io};
  beast::flat_buffer buffer;

  explicit Client(uint16_t port) {
    net::ip::tcp::resolver resolver(io);
    net::connect(ws.next_layer(), resolver.resolve("127.0.0.1", std::to_string(port)));
    ws.set_option(websocket::stream_base::decorator([](websocket::request_type& r) {
      r.set(beast::http::field::sec_websocket_protocol, "foxglove.websocket.v1");
    }));
    ws.handshake("127.0.0.1", "/");
  }
  /// The next message; `binary` says which kind it was.
  std::string read(bool& binary) {
    buffer.clear();
    ws.read(buffer);
    binary = ws.got_binary();
    return beast::buffers_to_string(buffer.data());
  }
  Json read_json() {
    bool binary = true;
    const auto s = read(binary);
    REQUIRE_FALSE(binary);
    return Json::parse(s);
  }
};

}  // namespace

TEST_CASE("websocket frame headers: FIN and the opcode, no mask, the length in 7, 16 or 64 bits") {
  for (const size_t n : {size_t{2}, size_t{125}, size_t{126}, size_t{65535}, size_t{65536}, size_t{70000}}) {
    std::string out;
    append_websocket_frame(out, true, "ab", std::string(n - 2, 'x'));
    CHECK(static_cast<uint8_t>(out[0]) == 0x82);
    const auto byte = [&](size_t i) { return static_cast<uint64_t>(static_cast<uint8_t>(out[i])); };
    const uint64_t code = byte(1);  // the mask bit is 0x80
    uint64_t length = code;
    size_t header = 2;
    if (code == 126) length = byte(2) << 8 | byte(3), header = 4;
    if (code == 127) {
      length = 0, header = 10;
      for (size_t i = 2; i < 10; ++i) length = length << 8 | byte(i);
    }
    CHECK(length == n);
    CHECK(header == (n < 126 ? 2 : n < 65536 ? 4 : 10));
    CHECK(out.size() == header + n);
    CHECK(out.substr(header, 3) == (n > 2 ? "abx" : "ab"));
  }
  std::string text;
  append_websocket_frame(text, false, "", "{}");
  CHECK(text == std::string("\x81\x02{}"));
}

TEST_CASE("the bridge's messages of every size reach Beast's client whole and in order") {
  FoxgloveBridge bridge(FoxgloveBridgeOptions{.port = 0});
  Client client(bridge.port());
  CHECK(client.read_json()["op"] == "serverInfo");

  bridge.on_lcm("TRAJECTORY", trajectory(0, 1).data(), trajectory(0, 1).size());  // advertises its channels
  std::map<std::string, uint32_t> channels;
  while (!channels.count("TRAJECTORY")) {
    const Json advertised = client.read_json();
    for (const auto& c : advertised["channels"]) channels[c["topic"]] = c["id"];
  }
  client.ws.write(net::buffer(
      Json{{"op", "subscribe"}, {"subscriptions", Json::array({{{"id", 7}, {"channelId", channels["TRAJECTORY"]}}})}}
          .dump()));
  // The subscription takes effect on the bridge's I/O thread.
  for (int i = 0; i < 500 && bridge.stats().clients.at(0).subscriptions == 0; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  REQUIRE(bridge.stats().clients.at(0).subscriptions == 1);
  const std::vector<int> sizes = {0, 1, 400, 1200};  // JSON forms of under 126 bytes to over 65536
  int64_t seq = 1;
  for (int round = 0; round < 20; ++round)
    for (int k : sizes) {
      const auto b = trajectory(seq++, k);
      bridge.on_lcm("TRAJECTORY", b.data(), b.size());
    }
  size_t largest = 0;
  for (int64_t expect = 1; expect < seq; ++expect) {
    bool binary = false;
    std::string m = client.read(binary);
    // Advertisements of the other topics may come between; so may the advertising message (seq 0), when the
    // subscription took effect before the bridge's mapping thread handed it out.
    while (!binary || (m.size() > 13 && expect == 1 && Json::parse(m.substr(13))["seq"] == 0)) {
      if (!binary) CHECK(Json::parse(m)["op"] == "advertise");
      m = client.read(binary);
    }
    REQUIRE(m.size() > 13);
    CHECK(static_cast<uint8_t>(m[0]) == 1);  // message data
    CHECK(static_cast<uint8_t>(m[1]) == 7);  // the subscription id, little-endian
    const Json j = Json::parse(m.substr(13));
    REQUIRE(j["seq"] == expect);
    CHECK(j["keyframes"].size() == static_cast<size_t>(sizes[(expect - 1) % sizes.size()]));
    largest = std::max(largest, m.size());
  }
  CHECK(largest > 65536);
  CHECK(bridge.stats().clients.at(0).dropped == 0);
}
