#include "viewer/foxglove_bridge.hpp"

#include "daemon/runtime/version.hpp"
#include "viewer/batched_write_stream.hpp"

#include <boost/asio/dispatch.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/strand.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <map>
#include <mutex>
#include <thread>

namespace sextant::viewer {
namespace {

namespace net = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = net::ip::tcp;

constexpr const char* kSubprotocol = "foxglove.websocket.v1";
constexpr uint8_t kMessageData = 0x01;  // server binary opcode
// A client's queued messages go out in writes of about this size: enough to make the system calls few, small
// enough that the batch being written adds little to the queue's bound.
constexpr size_t kBatchBytes = 256u << 10;

/// One WebSocket message queued for a client: a text control message, or a binary message-data frame whose
/// payload is shared by every client it goes to.
struct Frame {
  bool binary = false;
  std::array<char, 13> header{};  // opcode, subscription id (u32 LE), timestamp (u64 LE)
  std::shared_ptr<const std::string> payload;
  size_t size() const { return (binary ? header.size() : 0) + payload->size(); }
  std::string_view prefix() const { return {header.data(), binary ? header.size() : 0}; }
};

/// A viewer message mapped from the bus, for every client that subscribes to its channel.
struct Outgoing {
  uint32_t channel;
  uint64_t timestamp;  // when the bridge received its LCM message
  std::shared_ptr<const std::string> payload;
};

Frame control(const Json& j) { return Frame{false, {}, std::make_shared<const std::string>(j.dump())}; }

Json advertisement(uint32_t id, const ViewerMessage& m) {
  return Json{{"id", id},
              {"topic", m.topic},
              {"encoding", "json"},
              {"schemaName", m.schema->name},
              {"schema", m.schema->data},
              {"schemaEncoding", m.schema->encoding}};
}

uint64_t now_ns() {
  return static_cast<uint64_t>(
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
          .count());
}

}  // namespace

class Session;

struct FoxgloveBridge::Impl {
  FoxgloveBridgeOptions options;
  TopicMapper mapper;  // used by the mapping thread only
  std::vector<ViewerMessage> scratch;

  // The LCM thread only copies each message into this bounded queue, so that it drains the socket at once however
  // long the mapping takes (a burst of datagrams would otherwise overflow the kernel's receive buffer).  The mapping
  // thread takes what is there at once and hands each client the batch's messages together.
  struct Received {
    uint64_t time_ns;
    std::string channel;
    std::vector<uint8_t> data;
  };
  std::mutex input_mutex;
  std::condition_variable input_ready;
  std::deque<Received> input;
  size_t input_bytes = 0;
  bool stopping = false;
  std::thread mapping;

  net::io_context io{1};
  tcp::acceptor acceptor{io};
  std::thread thread;

  mutable std::mutex mutex;                                             // guards what follows
  std::map<std::pair<std::string, std::string>, uint32_t> channel_ids;  // (topic, schema) -> channel id
  std::vector<Json> advertised;                                         // by channel id - 1
  std::vector<std::shared_ptr<Session>> sessions;
  FoxgloveBridgeStats totals;

  void accept();
  void map_loop();
  void map_one(const Received& r, std::vector<Outgoing>& out);
  void take_mapped(uint64_t time_ns, std::vector<Outgoing>& out);
  void add_session(const std::shared_ptr<Session>& s);
  void remove_session(const Session* s);
  uint32_t channel_for(const ViewerMessage& m);
};

/// One client connection, its subscriptions and its bounded queue.  Socket work runs on the I/O thread; offer() and
/// send() may be called from any thread.
class Session : public std::enable_shared_from_this<Session> {
 public:
  Session(tcp::socket socket, FoxgloveBridge::Impl& bridge) : ws_(std::move(socket)), bridge_(bridge) {
    beast::error_code ec;
    const auto ep = beast::get_lowest_layer(ws_).socket().remote_endpoint(ec);
    address_ = ec ? "?" : ep.address().to_string() + ":" + std::to_string(ep.port());
    // The writer batches; Nagle's algorithm would only hold a batch back until the previous one is acknowledged
    // (with the viewer's delayed acknowledgement, tens of milliseconds).
    beast::get_lowest_layer(ws_).socket().set_option(tcp::no_delay(true), ec);
  }

  void run() {
    net::dispatch(ws_.get_executor(), [self = shared_from_this()] { self->read_request(); });
  }

  /// Queues a control message (never dropped).
  void send(const Json& j) { enqueue(control(j), false); }

  /// Queues the messages of `batch` whose channels this client subscribes to.
  void offer(const std::vector<Outgoing>& batch) {
    std::lock_guard lock(mutex_);
    if (closed_) return;
    for (const auto& o : batch) {
      const auto sub = by_channel_.find(o.channel);
      if (sub == by_channel_.end()) continue;
      Frame f{true, {}, o.payload};
      f.header[0] = static_cast<char>(kMessageData);
      for (int i = 0; i < 4; ++i) f.header[1 + i] = static_cast<char>(sub->second >> (8 * i));
      for (int i = 0; i < 8; ++i) f.header[5 + i] = static_cast<char>(o.timestamp >> (8 * i));
      append(std::move(f), true);
    }
    wake();
  }

  FoxgloveClientStats stats() const {
    std::lock_guard lock(mutex_);
    return {address_, static_cast<int64_t>(subscriptions_.size()), sent_, dropped_, queue_.size(), queued_max_};
  }

 private:
  struct Queued {
    Frame frame;
    bool droppable;
  };

  void enqueue(Frame f, bool droppable) {
    std::lock_guard lock(mutex_);
    if (!closed_) push(std::move(f), droppable);
  }

  // With mutex_ held: append and wake the writer.
  void push(Frame f, bool droppable) {
    append(std::move(f), droppable);
    wake();
  }

  // With mutex_ held: append, dropping the oldest droppable messages while over the bounds.
  void append(Frame f, bool droppable) {
    queued_bytes_ += f.size();
    queue_.push_back({std::move(f), droppable});
    while (queue_.size() > bridge_.options.max_queued_messages || queued_bytes_ > bridge_.options.max_queued_bytes) {
      auto oldest = std::find_if(queue_.begin(), queue_.end(), [](const Queued& q) { return q.droppable; });
      if (oldest == queue_.end()) break;
      queued_bytes_ -= oldest->frame.size();
      queue_.erase(oldest);
      ++dropped_;
    }
    queued_max_ = std::max(queued_max_, queue_.size());
  }

  // With mutex_ held: start the writer unless it is running (it takes whatever is queued when it runs).
  void wake() {
    if (!writing_ && accepted_ && !queue_.empty()) {
      writing_ = true;
      net::post(ws_.get_executor(), [self = shared_from_this()] { self->write_next(); });
    }
  }

  // ---- the handshake: an HTTP upgrade offering the Foxglove subprotocol ----
  void read_request() {
    beast::get_lowest_layer(ws_).expires_after(std::chrono::seconds(10));
    http::async_read(ws_.next_layer(), buffer_, request_, [self = shared_from_this()](beast::error_code ec, size_t) {
      if (ec) return self->close();
      self->on_request();
    });
  }

  void on_request() {
    const auto offered = std::string(request_[http::field::sec_websocket_protocol]);
    if (!websocket::is_upgrade(request_) || offered.find(kSubprotocol) == std::string::npos) {
      refuse(std::string("this is a Foxglove WebSocket server: connect with the ") + kSubprotocol + " subprotocol");
      return;
    }
    beast::get_lowest_layer(ws_).expires_never();
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    ws_.set_option(websocket::stream_base::decorator([](websocket::response_type& res) {
      res.set(http::field::sec_websocket_protocol, kSubprotocol);
      res.set(http::field::server, std::string("sextant ") + sextant::version());
    }));
    ws_.read_message_max(1 << 20);  // clients send small JSON requests only
    ws_.async_accept(request_, [self = shared_from_this()](beast::error_code ec) {
      if (ec) return self->close();
      {
        std::lock_guard lock(self->mutex_);
        self->accepted_ = true;
      }
      self->bridge_.add_session(self);  // queues serverInfo and the advertisements, then starts the writer
      self->read_next();
    });
  }

  void refuse(const std::string& why) {
    {
      std::lock_guard lock(bridge_.mutex);
      ++bridge_.totals.rejected_connections;
    }
    auto res = std::make_shared<http::response<http::string_body>>(http::status::bad_request, request_.version());
    res->set(http::field::content_type, "text/plain");
    res->body() = why + "\n";
    res->prepare_payload();
    http::async_write(ws_.next_layer(), *res,
                      [self = shared_from_this(), res](beast::error_code, size_t) { self->close(); });
  }

  // ---- what the client asks: subscribe and unsubscribe; anything else is answered with a status message ----
  void read_next() {
    ws_.async_read(buffer_, [self = shared_from_this()](beast::error_code ec, size_t) {
      if (ec) return self->close();
      const bool text = self->ws_.got_text();
      const std::string data = beast::buffers_to_string(self->buffer_.data());
      self->buffer_.consume(self->buffer_.size());
      self->on_client_message(text, data);
      self->read_next();
    });
  }

  void status(int level, const std::string& message) {
    send(Json{{"op", "status"}, {"level", level}, {"message", message}});
  }

  void on_client_message(bool text, const std::string& data) {
    if (!text) return status(2, "this server accepts no client messages (no client publishing)");
    Json j;
    try {
      j = Json::parse(data);
    } catch (const std::exception& e) {
      return status(2, std::string("not JSON: ") + e.what());
    }
    const std::string op = j.is_object() && j.contains("op") && j["op"].is_string() ? j["op"].get<std::string>() : "";
    try {
      if (op == "subscribe") {
        for (const auto& s : j.at("subscriptions"))
          subscribe(s.at("id").get<uint32_t>(), s.at("channelId").get<uint32_t>());
      } else if (op == "unsubscribe") {
        for (const auto& id : j.at("subscriptionIds")) unsubscribe(id.get<uint32_t>());
      } else {
        status(1, "unsupported op '" + op + "': this server offers subscriptions only");
      }
    } catch (const std::exception& e) {
      status(2, "malformed " + op + ": " + e.what());
    }
  }

  void subscribe(uint32_t id, uint32_t channel) {
    {
      std::lock_guard lock(bridge_.mutex);
      if (channel == 0 || channel > bridge_.advertised.size())
        return status(2, "unknown channel " + std::to_string(channel));
    }
    std::lock_guard lock(mutex_);
    if (subscriptions_.count(id) || by_channel_.count(channel)) {
      push(control(Json{{"op", "status"},
                        {"level", 2},
                        {"message", "subscription " + std::to_string(id) + " or channel " + std::to_string(channel) +
                                        " already subscribed"}}),
           false);
      return;
    }
    subscriptions_[id] = channel;
    by_channel_[channel] = id;
  }

  void unsubscribe(uint32_t id) {
    std::lock_guard lock(mutex_);
    const auto it = subscriptions_.find(id);
    if (it == subscriptions_.end()) return;
    by_channel_.erase(it->second);
    subscriptions_.erase(it);
  }

  // ---- the writer, on the I/O thread: what is queued (up to kBatchBytes) framed into one write; the next batch
  // once it is written, so that a client that does not read holds one batch here and the rest in its queue ----
  void write_next() {
    batch_.clear();
    {
      std::lock_guard lock(mutex_);
      if (queue_.empty() || closed_) {
        writing_ = false;
        return;
      }
      for (size_t bytes = 0; !queue_.empty() && bytes < kBatchBytes; queue_.pop_front()) {
        bytes += queue_.front().frame.size();
        queued_bytes_ -= queue_.front().frame.size();
        batch_.push_back(std::move(queue_.front().frame));
      }
    }
    auto& stream = ws_.next_layer();
    for (const auto& f : batch_) append_websocket_frame(stream.pending(), f.binary, f.prefix(), *f.payload);
    const auto n = static_cast<int64_t>(batch_.size());
    batch_.clear();  // the payloads are copied: release them now
    stream.flush([self = shared_from_this(), n](beast::error_code ec) {
      if (ec) return self->close();
      {
        std::lock_guard lock(self->mutex_);
        self->sent_ += n;
      }
      self->write_next();
    });
  }

  void close() {
    {
      std::lock_guard lock(mutex_);
      if (closed_) return;
      closed_ = true;
      queue_.clear();
    }
    beast::error_code ec;
    beast::get_lowest_layer(ws_).socket().shutdown(tcp::socket::shutdown_both, ec);
    bridge_.remove_session(this);
  }

  websocket::stream<BatchedWriteStream> ws_;
  FoxgloveBridge::Impl& bridge_;
  std::string address_;
  beast::flat_buffer buffer_;
  http::request<http::string_body> request_;
  std::vector<Frame> batch_;  // the writer's, reused

  mutable std::mutex mutex_;  // guards what follows
  std::deque<Queued> queue_;
  size_t queued_bytes_ = 0, queued_max_ = 0;
  bool writing_ = false, accepted_ = false, closed_ = false;
  std::map<uint32_t, uint32_t> subscriptions_;  // subscription id -> channel id
  std::map<uint32_t, uint32_t> by_channel_;     // channel id -> subscription id
  int64_t sent_ = 0, dropped_ = 0;
};

void FoxgloveBridge::Impl::accept() {
  acceptor.async_accept(net::make_strand(io), [this](beast::error_code ec, tcp::socket socket) {
    if (!ec) std::make_shared<Session>(std::move(socket), *this)->run();
    if (acceptor.is_open()) accept();
  });
}

void FoxgloveBridge::Impl::add_session(const std::shared_ptr<Session>& s) {
  std::lock_guard lock(mutex);
  sessions.push_back(s);
  ++totals.clients_connected;
  s->send(Json{{"op", "serverInfo"},
               {"name", options.name},
               {"capabilities", Json::array()},
               {"supportedEncodings", Json::array()},
               {"metadata", Json{{"version", sextant::version()}}},
               {"sessionId", std::to_string(now_ns())}});
  if (!advertised.empty()) s->send(Json{{"op", "advertise"}, {"channels", advertised}});
}

void FoxgloveBridge::Impl::remove_session(const Session* s) {
  std::lock_guard lock(mutex);
  sessions.erase(std::remove_if(sessions.begin(), sessions.end(), [s](const auto& p) { return p.get() == s; }),
                 sessions.end());
}

uint32_t FoxgloveBridge::Impl::channel_for(const ViewerMessage& m) {
  std::lock_guard lock(mutex);
  const auto key = std::make_pair(m.topic, m.schema->name);
  if (const auto it = channel_ids.find(key); it != channel_ids.end()) return it->second;
  const auto id = static_cast<uint32_t>(advertised.size() + 1);
  channel_ids.emplace(key, id);
  advertised.push_back(advertisement(id, m));
  ++totals.channels;
  for (const auto& s : sessions) s->send(Json{{"op", "advertise"}, {"channels", Json::array({advertised.back()})}});
  return id;
}

FoxgloveBridge::FoxgloveBridge(FoxgloveBridgeOptions options, TopicMapperOptions mapping)
    : impl_(std::make_shared<Impl>()) {
  impl_->options = std::move(options);
  mapping.batch_frame_transforms = true;  // one /tf message per batch mapped together
  impl_->mapper = TopicMapper(mapping);
  const std::string where = impl_->options.bind_address + ":" + std::to_string(impl_->options.port);
  try {
    const tcp::endpoint ep(net::ip::make_address(impl_->options.bind_address), impl_->options.port);
    impl_->acceptor.open(ep.protocol());
    impl_->acceptor.set_option(net::socket_base::reuse_address(true));
    impl_->acceptor.bind(ep);
    impl_->acceptor.listen();
  } catch (const std::exception& e) {
    throw std::runtime_error("cannot listen on " + where + ": " + e.what());
  }
  impl_->accept();
  impl_->thread = std::thread([impl = impl_.get()] { impl->io.run(); });
  impl_->mapping = std::thread([impl = impl_.get()] { impl->map_loop(); });
}

FoxgloveBridge::~FoxgloveBridge() {
  {
    std::lock_guard lock(impl_->input_mutex);
    impl_->stopping = true;
  }
  impl_->input_ready.notify_one();
  impl_->mapping.join();
  net::post(impl_->io, [impl = impl_.get()] {
    beast::error_code ec;
    impl->acceptor.close(ec);
  });
  impl_->io.stop();
  impl_->thread.join();
  std::lock_guard lock(impl_->mutex);
  impl_->sessions.clear();
}

uint16_t FoxgloveBridge::port() const { return impl_->acceptor.local_endpoint().port(); }

void FoxgloveBridge::on_lcm(const std::string& channel, const uint8_t* data, size_t size) {
  auto& impl = *impl_;
  {
    std::lock_guard lock(impl.input_mutex);
    impl.input.push_back({now_ns(), channel, std::vector<uint8_t>(data, data + size)});
    impl.input_bytes += size;
    while (impl.input.size() > impl.options.max_input_messages || impl.input_bytes > impl.options.max_queued_bytes) {
      impl.input_bytes -= impl.input.front().data.size();
      impl.input.pop_front();
      std::lock_guard stats(impl.mutex);
      ++impl.totals.input_dropped;
    }
  }
  impl.input_ready.notify_one();
}

void FoxgloveBridge::Impl::map_loop() {
  std::deque<Received> batch;
  std::vector<Outgoing> out;
  while (true) {
    {
      std::unique_lock lock(input_mutex);
      input_ready.wait(lock, [this] { return stopping || !input.empty(); });
      if (input.empty()) return;  // stopping, and everything received was mapped
      batch.swap(input);
      input_bytes = 0;
    }
    out.clear();
    for (const auto& r : batch) {
      try {
        map_one(r, out);
      } catch (const std::exception&) {  // nothing leaves this thread; the message is lost and counted
        std::lock_guard lock(mutex);
        ++totals.mapping_failures;
      }
    }
    scratch.clear();
    mapper.flush(scratch);  // the batch's frame transforms, in one message
    take_mapped(batch.back().time_ns, out);
    batch.clear();
    std::vector<std::shared_ptr<Session>> targets;
    {
      std::lock_guard lock(mutex);
      targets = sessions;
    }
    for (const auto& s : targets) s->offer(out);
  }
}

// One LCM message through the viewer mapping: its viewer messages appended to `out`.
void FoxgloveBridge::Impl::map_one(const Received& r, std::vector<Outgoing>& out) {
  scratch.clear();
  mapper.map(r.channel, r.data.data(), r.data.size(), scratch);
  {
    std::lock_guard lock(mutex);
    ++totals.lcm_messages;
    totals.without_json = mapper.counts().raw;
  }
  take_mapped(r.time_ns, out);
}

// The viewer messages in `scratch`, received at `time_ns`, appended to `out`; their channels advertised.
void FoxgloveBridge::Impl::take_mapped(uint64_t time_ns, std::vector<Outgoing>& out) {
  for (auto& m : scratch)
    if (m.schema) out.push_back({channel_for(m), time_ns, std::make_shared<const std::string>(std::move(m.data))});
}

FoxgloveBridgeStats FoxgloveBridge::stats() const {
  std::vector<std::shared_ptr<Session>> sessions;
  FoxgloveBridgeStats out;
  {
    std::lock_guard lock(impl_->mutex);
    out = impl_->totals;
    sessions = impl_->sessions;
  }
  for (const auto& s : sessions) out.clients.push_back(s->stats());
  return out;
}

}  // namespace sextant::viewer
