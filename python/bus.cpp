// The `sextant` module's live LCM bus through liblcm's C API: publish, subscribe with decoded or raw callbacks,
// handle with the GIL released and Ctrl-C honoured.
#include "python/module_parts.hpp"

#include "daemon/runtime/daemon.hpp"

#include <lcm/lcm.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <chrono>
#include <map>
#include <memory>
#include <optional>

namespace sextant::python {
namespace {

class Bus {
 public:
  explicit Bus(const std::string& url) : url_(url) {
    lcm_ = lcm_create(url.empty() ? nullptr : url.c_str());
    if (lcm_ == nullptr) throw std::runtime_error(runtime::bus_failure_help(url));
  }
  ~Bus() { close(); }
  Bus(const Bus&) = delete;
  Bus& operator=(const Bus&) = delete;

  void close() {
    if (lcm_ == nullptr) return;
    for (auto& [id, s] : subs_) lcm_unsubscribe(lcm_, s->subscription);
    subs_.clear();
    lcm_destroy(lcm_);
    lcm_ = nullptr;
  }

  void publish(const std::string& channel, const py::bytes& data) {
    const auto v = bytes_view(data);
    if (lcm_publish(get(), channel.c_str(), v.data(), static_cast<unsigned>(v.size())) != 0)
      throw std::runtime_error("cannot publish on " + channel + " (" + std::to_string(v.size()) + " bytes)");
  }

  void publish_message(const std::string& channel, const std::string& type, const py::handle& msg) {
    publish(channel, to_bytes(type_by_name(type).encode(msg)));
  }

  int subscribe(const std::string& channel, py::function callback, bool raw, int queue_capacity) {
    if (queue_capacity < 1) throw py::value_error("queue_capacity must be at least 1");
    auto s = std::make_unique<Subscription>();
    s->bus = this;
    s->callback = std::move(callback);
    s->raw = raw;
    s->subscription = lcm_subscribe(get(), channel.c_str(), &Bus::on_message, s.get());
    if (s->subscription == nullptr) throw std::runtime_error("cannot subscribe to " + channel);
    // liblcm keeps 30 undelivered messages per subscription unless told otherwise and silently drops the rest: a
    // Python loop that falls behind a 50 Hz channel for a second would lose messages without a word.
    lcm_subscription_set_queue_capacity(s->subscription, queue_capacity);
    const int id = next_id_++;
    subs_[id] = std::move(s);
    return id;
  }

  void unsubscribe(int id) {
    const auto it = subs_.find(id);
    if (it == subs_.end()) throw py::value_error("no subscription " + std::to_string(id));
    lcm_unsubscribe(get(), it->second->subscription);
    subs_.erase(it);
  }

  // Waits up to `timeout` seconds (None: until a message comes) for one message and dispatches it to the matching
  // callbacks; True when one was handled.  Waits in slices so Ctrl-C interrupts it.
  bool handle(std::optional<double> timeout) {
    using Clock = std::chrono::steady_clock;
    const auto deadline = timeout ? Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                                       std::chrono::duration<double>(std::max(0.0, *timeout)))
                                  : Clock::time_point::max();
    for (;;) {
      int slice_ms = 100;
      if (timeout) {
        const double left = std::chrono::duration<double, std::milli>(deadline - Clock::now()).count();
        slice_ms = static_cast<int>(std::clamp(left, 0.0, 100.0));
      }
      int rc = 0;
      {
        py::gil_scoped_release release;
        rc = lcm_handle_timeout(get(), slice_ms);
      }
      if (pending_) {
        auto e = std::move(pending_);
        throw *e;
      }
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
      if (rc < 0)
        throw std::runtime_error("LCM: handling failed on " + (url_.empty() ? std::string("the default URL") : url_));
      if (rc > 0) return true;
      if (timeout && Clock::now() >= deadline) return false;
    }
  }

  int fileno() { return lcm_get_fileno(get()); }

 private:
  struct Subscription {
    Bus* bus = nullptr;
    py::function callback;
    bool raw = false;
    lcm_subscription_t* subscription = nullptr;
  };

  lcm_t* get() {
    if (lcm_ == nullptr) throw py::value_error("the bus is closed");
    return lcm_;
  }

  // Runs inside lcm_handle_timeout on the caller's thread: the callback's exception is kept and raised by handle().
  static void on_message(const lcm_recv_buf_t* rbuf, const char* channel, void* user) {
    auto* s = static_cast<Subscription*>(user);
    py::gil_scoped_acquire acquire;
    if (s->bus->pending_) return;
    try {
      py::bytes data(static_cast<const char*>(rbuf->data), rbuf->data_size);
      if (s->raw) {
        s->callback(channel, data);
        return;
      }
      const MessageType* t = type_of(rbuf->data, rbuf->data_size);
      py::object msg = data, type = py::none();
      if (t != nullptr) {
        try {
          msg = t->decode(rbuf->data, rbuf->data_size);
          type = py::str(t->name);
        } catch (const std::invalid_argument&) {}
      }
      s->callback(channel, type, msg);
    } catch (py::error_already_set& e) {
      s->bus->pending_ = std::make_unique<py::error_already_set>(std::move(e));
    }
  }

  std::string url_;
  lcm_t* lcm_ = nullptr;
  std::map<int, std::unique_ptr<Subscription>> subs_;
  int next_id_ = 1;
  std::unique_ptr<py::error_already_set> pending_;
};

}  // namespace

void register_bus(py::module_& m) {
  py::class_<Bus>(m, "Bus",
                  "A live LCM bus through liblcm; a context manager.  URL '' = LCM's default "
                  "(LCM_DEFAULT_URL or udpm://239.255.76.67:7667).")
      .def(py::init<const std::string&>(), py::arg("url") = "")
      .def("publish", &Bus::publish, py::arg("channel"), py::arg("data"), "Publishes raw bytes.")
      .def("publish_message", &Bus::publish_message, py::arg("channel"), py::arg("type"), py::arg("message"),
           "Encodes the dict as `type` and publishes it.")
      .def("subscribe", &Bus::subscribe, py::arg("channel"), py::arg("callback"), py::arg("raw") = false,
           py::arg("queue_capacity") = 10000,
           "Calls callback(channel, type, message) for each message on the channels matching the regex: message is "
           "the decoded dict, or the bytes with type None when it is no sextant message; raw=True: "
           "callback(channel, data).  Up to queue_capacity messages wait for handle() (liblcm drops beyond that; "
           "its own default is 30).  Returns an id for unsubscribe().")
      .def("unsubscribe", &Bus::unsubscribe, py::arg("id"))
      .def("handle", &Bus::handle, py::arg("timeout") = py::none(),
           "Waits up to timeout seconds (None: forever) for a message and runs its callbacks; True when one came.  "
           "A callback's exception is raised here.")
      .def("fileno", &Bus::fileno, "The bus's file descriptor, for select().")
      .def("close", &Bus::close)
      .def(
          "__enter__", [](Bus& b) -> Bus& { return b; }, py::return_value_policy::reference_internal)
      .def("__exit__", [](Bus& b, py::args) { b.close(); });
}

}  // namespace sextant::python
