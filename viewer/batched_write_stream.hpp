#pragma once
// The TCP stream under the bridge's WebSocket stream: reads pass through, and every write goes through one buffer
// that a single flush at a time sends with one system call.  Beast writes one WebSocket message per system call and
// wakes the viewer once per message; a viewer subscribed to everything receives thousands of small messages a
// second, so the bridge frames a client's queued messages itself (websocket_frame) and hands them over in one go.
// Beast's own writes (the handshake response, pongs, pings, the close frame) go through the same buffer, so the
// two never interleave on the socket.
#include <boost/asio/post.hpp>
#include <boost/asio/write.hpp>
#include <boost/beast/core/tcp_stream.hpp>
#include <boost/beast/websocket/teardown.hpp>

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace sextant::viewer {

/// Appends one unmasked, unfragmented WebSocket data frame (RFC 6455 section 5.2: a server's frames carry no mask)
/// holding `prefix` then `payload`, as binary or text.
inline void append_websocket_frame(std::string& out, bool binary, std::string_view prefix, std::string_view payload) {
  const uint64_t n = prefix.size() + payload.size();
  char header[10] = {static_cast<char>(0x80 | (binary ? 0x2 : 0x1))};  // FIN, opcode
  size_t size = 2;
  if (n < 126) {
    header[1] = static_cast<char>(n);
  } else if (n < 65536) {
    header[1] = 126;
    for (int i = 0; i < 2; ++i) header[2 + i] = static_cast<char>(n >> (8 * (1 - i)));  // big-endian
    size = 4;
  } else {
    header[1] = 127;
    for (int i = 0; i < 8; ++i) header[2 + i] = static_cast<char>(n >> (8 * (7 - i)));
    size = 10;
  }
  out.append(header, size);
  out.append(prefix);
  out.append(payload);
}

class BatchedWriteStream {
 public:
  using executor_type = boost::beast::tcp_stream::executor_type;
  using next_layer_type = boost::beast::tcp_stream;
  using Done = std::function<void(boost::beast::error_code)>;

  explicit BatchedWriteStream(boost::asio::ip::tcp::socket socket) : next_(std::move(socket)) {}

  executor_type get_executor() { return next_.get_executor(); }
  next_layer_type& next_layer() { return next_; }

  /// The bytes waiting for the next flush: append whole frames, then call flush().
  std::string& pending() { return pending_; }

  /// Sends what is pending after what is being sent; `done` runs once it is written or the stream failed (never
  /// from within this call).
  void flush(Done done) {
    if (error_) {
      boost::asio::post(get_executor(), [done = std::move(done), ec = error_] { done(ec); });
      return;
    }
    pending_done_.push_back(std::move(done));
    if (!sending_) send();
  }

  template <class MutableBuffers, class Handler>
  auto async_read_some(const MutableBuffers& buffers, Handler&& handler) {
    return next_.async_read_some(buffers, std::forward<Handler>(handler));
  }

  /// Beast's writes: appended, completed once flushed (all or nothing).
  template <class ConstBuffers, class Token>
  auto async_write_some(const ConstBuffers& buffers, Token&& token) {
    return boost::asio::async_initiate<Token, void(boost::beast::error_code, std::size_t)>(
        [this](auto handler, const ConstBuffers& b) {
          const size_t n = boost::asio::buffer_size(b);
          for (auto it = boost::asio::buffer_sequence_begin(b); it != boost::asio::buffer_sequence_end(b); ++it) {
            const boost::asio::const_buffer c = *it;
            pending_.append(static_cast<const char*>(c.data()), c.size());
          }
          // A std::function must be copyable; completion handlers are move-only.
          auto h = std::make_shared<decltype(handler)>(std::move(handler));
          flush([h, n](boost::beast::error_code ec) { (*h)(ec, ec ? 0 : n); });
        },
        token, buffers);
  }

 private:
  void send() {
    sending_ = true;
    sending_bytes_.swap(pending_);
    pending_.clear();
    sending_done_.swap(pending_done_);
    pending_done_.clear();
    boost::asio::async_write(next_, boost::asio::buffer(sending_bytes_), [this](boost::beast::error_code ec, size_t) {
      sending_ = false;
      if (ec) error_ = ec;
      std::vector<Done> done;
      done.swap(sending_done_);
      if (!error_ && !pending_done_.empty()) send();
      if (error_) {  // what was queued meanwhile fails too
        for (auto& d : pending_done_) done.push_back(std::move(d));
        pending_done_.clear();
      }
      for (auto& d : done) d(error_);
    });
  }

  next_layer_type next_;
  std::string pending_, sending_bytes_;
  std::vector<Done> pending_done_, sending_done_;
  bool sending_ = false;
  boost::beast::error_code error_;
};

/// Closing the WebSocket connection: what is queued goes out first, then the TCP connection is shut down.
template <class TeardownHandler>
void async_teardown(boost::beast::role_type role, BatchedWriteStream& stream, TeardownHandler&& handler) {
  auto h = std::make_shared<std::decay_t<TeardownHandler>>(std::forward<TeardownHandler>(handler));
  stream.flush([&stream, role, h](boost::beast::error_code) {
    using boost::beast::websocket::async_teardown;
    async_teardown(role, stream.next_layer(), std::move(*h));
  });
}

}  // namespace sextant::viewer
