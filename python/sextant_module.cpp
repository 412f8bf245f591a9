// The `sextant` Python module: LCM logs, every sextant message as a dict, a live LCM bus through liblcm (no LCM
// Python package needed), `sextant optimize` and `sextant eval` as functions returning the CLI's JSON keys.
// See the README's Python section; tests in tests/python/.
#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/daemon.hpp"
#include "daemon/runtime/lcm_log.hpp"
#include "daemon/runtime/version.hpp"
#include "python/message_dicts.hpp"
#include "replay/graph_optimization.hpp"
#include "replay/trajectory_evaluation.hpp"

#include <lcm/lcm.h>
#include <pybind11/stl.h>

#include <chrono>
#include <cstdio>
#include <map>
#include <memory>
#include <optional>
#include <sstream>

namespace py = pybind11;
using namespace sextant;
using sextant::python::MessageType;

namespace {

// ---------------------------------------------------------------- messages

const MessageType& type_by_name(const std::string& name) {
  for (const auto& t : python::message_types())
    if (t.name == name) return t;
  std::string list;
  for (const auto& t : python::message_types()) list += (list.empty() ? "" : ", ") + t.name;
  throw py::value_error("unknown message type '" + name + "' (types: " + list + ")");
}

/// The type whose fingerprint the bytes start with (LCM's 8-byte big-endian hash), or nullptr.
const MessageType* type_of(const void* data, size_t size) {
  if (size < 8) return nullptr;
  const auto* b = static_cast<const uint8_t*>(data);
  uint64_t h = 0;
  for (int i = 0; i < 8; ++i) h = (h << 8) | b[i];
  for (const auto& t : python::message_types())
    if (static_cast<uint64_t>(t.fingerprint) == h) return &t;
  return nullptr;
}

std::string_view bytes_view(const py::bytes& b) {
  char* p = nullptr;
  Py_ssize_t n = 0;
  if (PyBytes_AsStringAndSize(b.ptr(), &p, &n) != 0) throw py::error_already_set();
  return {p, static_cast<size_t>(n)};
}

py::bytes to_bytes(const std::vector<uint8_t>& v) {
  return py::bytes(reinterpret_cast<const char*>(v.data()), v.size());
}

py::dict decode(const py::bytes& data, const std::optional<std::string>& type) {
  const auto v = bytes_view(data);
  if (type) return type_by_name(*type).decode(v.data(), v.size());
  const MessageType* t = type_of(v.data(), v.size());
  if (t == nullptr)
    throw py::value_error("not a sextant message: its fingerprint matches none of the " +
                          std::to_string(python::message_types().size()) + " types (pass type= to decode anyway)");
  return t->decode(v.data(), v.size());
}

py::object message_type_of(const py::bytes& data) {
  const auto v = bytes_view(data);
  const MessageType* t = type_of(v.data(), v.size());
  return t ? py::object(py::str(t->name)) : py::object(py::none());
}

py::bytes encode(const std::string& type, const py::handle& message) { return to_bytes(type_by_name(type).encode(message)); }

// The daemon's own validation of an input message (daemon/runtime/codec.hpp): None when it would be accepted, else
// (reason, message) as counted on SEXTANT_STATUS.
py::object validate(const std::string& kind, const py::bytes& data) {
  static const std::map<std::string, runtime::InputKind> kinds = {{"odometry", runtime::InputKind::kOdometry},
                                                                  {"landmarks", runtime::InputKind::kLandmarks},
                                                                  {"bearings", runtime::InputKind::kBearings},
                                                                  {"loop_closures", runtime::InputKind::kLoopClosures}};
  const auto it = kinds.find(kind);
  if (it == kinds.end())
    throw py::value_error("unknown input kind '" + kind + "' (kinds: odometry, landmarks, bearings, loop_closures)");
  const auto v = bytes_view(data);
  const runtime::Decoded d = runtime::decode_event(it->second, v.data(), v.size());
  if (const auto* r = std::get_if<runtime::Rejection>(&d)) return py::make_tuple(r->reason, r->message);
  return py::none();
}

// ---------------------------------------------------------------- logs

py::tuple record_tuple(const runtime::LogRecord& r) { return py::make_tuple(r.timestamp, r.channel, to_bytes(r.data)); }

class PyLogReader {
 public:
  explicit PyLogReader(const std::string& path) : reader_(path) {}
  py::tuple next() {
    auto r = reader_.next();
    if (!r) throw py::stop_iteration();
    return record_tuple(*r);
  }

 private:
  runtime::LogReader reader_;
};

class PyLogWriter {
 public:
  explicit PyLogWriter(const std::string& path) : writer_(std::make_unique<runtime::LogWriter>(path)) {}
  void write(int64_t timestamp, const std::string& channel, const py::bytes& data) {
    const auto v = bytes_view(data);
    open().write_raw(timestamp, channel, v.data(), v.size());
  }
  void write_message(int64_t timestamp, const std::string& channel, const std::string& type, const py::handle& msg) {
    const auto bytes = type_by_name(type).encode(msg);
    open().write_raw(timestamp, channel, bytes.data(), bytes.size());
  }
  void flush() { open().flush(); }
  void close() {
    if (writer_) writer_->flush();
    writer_.reset();
  }
  int64_t events_written() const { return writer_ ? writer_->events_written() : written_at_close_; }

 private:
  runtime::LogWriter& open() {
    if (!writer_) throw py::value_error("the log is closed");
    return *writer_;
  }
  std::unique_ptr<runtime::LogWriter> writer_;
  int64_t written_at_close_ = 0;
};

// ---------------------------------------------------------------- the bus

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
      if (rc < 0) throw std::runtime_error("LCM: handling failed on " + (url_.empty() ? std::string("the default URL") : url_));
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
        } catch (const std::invalid_argument&) {
        }
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

// ---------------------------------------------------------------- optimize, eval

py::object summary_value(const replay::SummaryValue& v) {
  return std::visit([](const auto& x) -> py::object { return py::cast(x); }, v);
}

py::dict summary_dict(const replay::Summary& s) {
  py::dict d;
  for (const auto& [k, v] : s.entries()) d[py::str(k)] = summary_value(v);
  return d;
}

bool is_path(const py::handle& obj) {
  return py::isinstance<py::str>(obj) || py::isinstance(obj, py::module_::import("os").attr("PathLike"));
}

// An in-memory graph: records that are g2o lines as sequences, ("VERTEX_SE2", 0, 0.0, 0.0, 0.0),
// ("EDGE_SE2", 0, 1, dx, dy, dtheta, I11, I12, ...), ("FIX", 0); parsed by the g2o reader itself, so the
// checks and messages are the file's, with "graph[K]" naming record K.
graph::G2oGraph graph_from_records(const py::handle& records) {
  std::ostringstream text;
  size_t k = 0;
  for (const py::handle rec : records) {
    if (!py::isinstance<py::sequence>(rec) || py::isinstance<py::str>(rec))
      throw py::value_error("graph[" + std::to_string(k) + "]: expected a sequence like ('VERTEX_SE2', id, x, y, theta)");
    bool first = true;
    for (const py::handle v : rec) {
      if (first) {
        if (!py::isinstance<py::str>(v)) throw py::value_error("graph[" + std::to_string(k) + "]: the first item must be the g2o tag");
        text << py::cast<std::string>(v);
        first = false;
      } else if (py::isinstance<py::int_>(v) && !py::isinstance<py::bool_>(v)) {
        text << ' ' << py::cast<long long>(v);
      } else if (py::isinstance<py::float_>(v)) {
        char buf[32];
        std::snprintf(buf, sizeof buf, "%.17g", py::cast<double>(v));
        text << ' ' << buf;
      } else {
        throw py::value_error("graph[" + std::to_string(k) + "]: expected numbers after the tag, got " +
                              python::type_name(v));
      }
    }
    if (first) throw py::value_error("graph[" + std::to_string(k) + "]: empty record");
    text << '\n';
    ++k;
  }
  std::istringstream in(text.str());
  try {
    return graph::read_g2o(in, "graph");
  } catch (const std::runtime_error& e) {
    // "graph:LINE: message" -> "graph[LINE-1]: message"
    std::string msg = e.what();
    const size_t colon = msg.find(':', 6);
    if (msg.rfind("graph:", 0) == 0 && colon != std::string::npos) {
      try {
        msg = "graph[" + std::to_string(std::stol(msg.substr(6, colon - 6)) - 1) + "]" + msg.substr(colon);
      } catch (const std::exception&) {
      }
    }
    throw py::value_error(msg);
  }
}

// Values in g2o's vertex order: SE2 [x, y, theta], SE3 [x, y, z, qx, qy, qz, qw], points [x, y] / [x, y, z].
py::list variable_values(const graph::Variable& v) {
  py::list l;
  switch (v.kind) {
    case graph::VariableKind::kPose2:
      for (double x : {v.pose2.translation().x(), v.pose2.translation().y(), v.pose2.rotation().angle()}) l.append(x);
      break;
    case graph::VariableKind::kPose3: {
      const auto& t = v.pose3.translation();
      const auto& q = v.pose3.rotation().quaternion();
      for (double x : {t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()}) l.append(x);
      break;
    }
    case graph::VariableKind::kPoint2:
      for (double x : {v.point.x(), v.point.y()}) l.append(x);
      break;
    case graph::VariableKind::kPoint3:
      for (double x : {v.point.x(), v.point.y(), v.point.z()}) l.append(x);
      break;
  }
  return l;
}

py::dict optimize(const py::object& graph_or_path, const std::optional<std::string>& output,
                  const replay::GraphOptimizationOptions& options) {
  graph::G2oGraph g = is_path(graph_or_path)
                          ? graph::read_g2o(py::cast<std::string>(py::str(graph_or_path)))
                          : graph_from_records(graph_or_path);
  replay::GraphOptimizationResult r;
  {
    py::gil_scoped_release release;
    r = replay::optimize_graph(g, options, output.value_or(""));
  }
  py::dict poses;
  for (const auto& v : r.variables) poses[py::int_(v.id)] = variable_values(v);
  py::dict out;
  out["summary"] = summary_dict(r.summary);
  out["poses"] = poses;
  out["ok"] = r.ok;
  out["message"] = r.message;
  return out;
}

// A trajectory: a TUM file's path, or rows [t, x, y, z, qx, qy, qz, qw] (seconds, metres, TUM's quaternion order).
std::vector<replay::StampedPose> trajectory(const py::object& obj, const char* what) {
  if (is_path(obj)) return replay::read_tum(py::cast<std::string>(py::str(obj)));
  std::vector<replay::StampedPose> poses;
  size_t k = 0;
  for (const py::handle row : obj) {
    const std::string where = std::string(what) + "[" + std::to_string(k++) + "]";
    const py::list l = python::as_list(row, where, 8);
    double v[8];
    for (size_t i = 0; i < 8; ++i) v[i] = python::read_number(l[i], where + "[" + std::to_string(i) + "]");
    replay::StampedPose p;
    p.t = v[0];
    p.pose.position = {v[1], v[2], v[3]};
    p.pose.orientation = Eigen::Quaterniond(v[7], v[4], v[5], v[6]);  // as read_tum: used as given
    poses.push_back(p);
  }
  // As read_tum: sorted by time, a repeated stamp replaces the earlier row.
  std::stable_sort(poses.begin(), poses.end(), [](const auto& a, const auto& b) { return a.t < b.t; });
  std::vector<replay::StampedPose> unique;
  for (const auto& p : poses) {
    if (!unique.empty() && unique.back().t == p.t) unique.back() = p;
    else unique.push_back(p);
  }
  return unique;
}

py::dict evaluate(const py::object& gt, const py::object& est, bool scale, double delta, const std::string& delta_unit,
                  double max_difference) {
  if (delta_unit != "s" && delta_unit != "f") throw py::value_error("delta_unit: 's' (seconds) or 'f' (frames)");
  if (!(delta > 0) || !(max_difference > 0)) throw py::value_error("delta and max_difference must be > 0");
  const replay::EvaluationOptions o{scale, delta, delta_unit == "f" ? replay::DeltaUnit::kFrames : replay::DeltaUnit::kSeconds,
                                    max_difference};
  const auto g = trajectory(gt, "gt"), e = trajectory(est, "est");
  return summary_dict(replay::evaluate_trajectory(g, e, o).summary(o));
}

}  // namespace

PYBIND11_MODULE(sextant, m) {
  m.doc() = "sextant: LCM logs, sextant messages as dicts, a live LCM bus, pose-graph optimization and trajectory "
            "evaluation (the `sextant` tool's optimize and eval)";
  m.attr("__version__") = sextant::version();

  m.def("message_types", [] {
    std::vector<std::string> names;
    for (const auto& t : python::message_types()) names.push_back(t.name);
    return names;
  }, "Names of every sextant message type (lcmtypes/sextant/*.lcm).");
  m.def("message_fields", [](const std::string& type) {
    py::list l;
    for (const auto& f : type_by_name(type).fields) l.append(py::make_tuple(f.name, f.type, f.dim));
    return l;
  }, py::arg("type"),
        "The fields of a message type as the .lcm file declares them: (name, lcm_type, dim), dim '' for a scalar, "
        "a number for a fixed array, the length field's name for a variable one.");
  m.def("decode", &decode, py::arg("data"), py::arg("type") = py::none(),
        "Decodes LCM bytes into a dict of the message's fields; the type comes from the bytes' fingerprint unless "
        "given.  ValueError for bytes that are no sextant message or do not decode.");
  m.def("message_type", &message_type_of, py::arg("data"), "The sextant type name of LCM bytes, or None.");
  m.def("encode", &encode, py::arg("type"), py::arg("message"),
        "Encodes a dict as the named message type.  Missing fields are zero (as in lcm-gen's classes); the length "
        "field of an array (num_*) follows the list.  ValueError naming the field for unknown keys or bad values.");
  m.def("validate", &validate, py::arg("kind"), py::arg("data"),
        "sextantd's own check of an input message: kind is odometry, landmarks, bearings or loop_closures.  None "
        "when the daemon would accept it, else (reason, message) as counted on SEXTANT_STATUS.");

  py::class_<PyLogReader>(m, "LogReader", "Iterates over an LCM log: (timestamp_us, channel, data) per event.")
      .def(py::init<const std::string&>(), py::arg("path"))
      .def("__iter__", [](PyLogReader& r) -> PyLogReader& { return r; }, py::return_value_policy::reference_internal)
      .def("__next__", &PyLogReader::next);
  m.def("read_log", [](const std::string& path) {
    py::list l;
    for (const auto& r : runtime::LogReader::read_all(path)) l.append(record_tuple(r));
    return l;
  }, py::arg("path"), "Every event of an LCM log as (timestamp_us, channel, data), in file order.");
  py::class_<PyLogWriter>(m, "LogWriter", "Writes an LCM log (lcm-logger's format); a context manager.")
      .def(py::init<const std::string&>(), py::arg("path"))
      .def("write", &PyLogWriter::write, py::arg("timestamp"), py::arg("channel"), py::arg("data"))
      .def("write_message", &PyLogWriter::write_message, py::arg("timestamp"), py::arg("channel"), py::arg("type"),
           py::arg("message"), "Encodes the dict as `type` and writes it.")
      .def("flush", &PyLogWriter::flush)
      .def("close", &PyLogWriter::close)
      .def_property_readonly("events_written", &PyLogWriter::events_written)
      .def("__enter__", [](PyLogWriter& w) -> PyLogWriter& { return w; }, py::return_value_policy::reference_internal)
      .def("__exit__", [](PyLogWriter& w, py::args) { w.close(); });

  py::class_<Bus>(m, "Bus", "A live LCM bus through liblcm; a context manager.  URL '' = LCM's default "
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
      .def("__enter__", [](Bus& b) -> Bus& { return b; }, py::return_value_policy::reference_internal)
      .def("__exit__", [](Bus& b, py::args) { b.close(); });

  m.def("optimize",
        [](const py::object& graph, const std::optional<std::string>& output, const std::string& solver,
           const std::string& init, const std::string& robust, double kernel_width, int max_iters, double tolerance,
           const std::string& ordering, bool incremental, double relin_translation, double relin_rotation,
           int relin_skip) {
          replay::GraphOptimizationOptions o;
          o.solver = solver, o.init = init, o.robust = robust, o.kernel_width = kernel_width;
          o.max_iters = max_iters, o.tolerance = tolerance, o.ordering = ordering, o.incremental = incremental;
          o.relin_translation = relin_translation, o.relin_rotation = relin_rotation, o.relin_skip = relin_skip;
          return optimize(graph, output, o);
        },
        py::arg("graph"), py::arg("output") = py::none(), py::arg("solver") = "gn", py::arg("init") = "file",
        py::arg("robust") = "none", py::arg("kernel_width") = 1.0, py::arg("max_iters") = 100,
        py::arg("tolerance") = 1e-6, py::arg("ordering") = "block-amd", py::arg("incremental") = false,
        py::arg("relin_translation") = 0.1, py::arg("relin_rotation") = 0.1, py::arg("relin_skip") = 1,
        "`sextant optimize`: graph is a g2o file's path or a list of g2o records such as ('VERTEX_SE2', 0, x, y, "
        "theta), ('EDGE_SE2', 0, 1, dx, dy, dtheta, *information_upper_triangle), ('FIX', 0).  Returns {'summary': "
        "the keys of `sextant optimize --json`, 'poses': {id: values in g2o's vertex order}, 'ok', 'message'}; "
        "output= also writes the optimized graph as g2o.");
  m.def("eval", &evaluate, py::arg("gt"), py::arg("est"), py::arg("scale") = false, py::arg("delta") = 1.0,
        py::arg("delta_unit") = "s", py::arg("max_difference") = 0.02,
        "`sextant eval`: ATE and RPE (TUM benchmark semantics) of est against gt, each a TUM file's path or rows "
        "[t, x, y, z, qx, qy, qz, qw].  Returns the keys of `sextant eval --json`.");
}
