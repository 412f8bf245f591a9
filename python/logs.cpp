// The `sextant` module's LCM logs (lcm-logger's format) through daemon/runtime/lcm_log.hpp.
#include "python/module_parts.hpp"

#include "daemon/runtime/lcm_log.hpp"

#include <memory>

namespace sextant::python {
namespace {

py::tuple record_tuple(const runtime::LogRecord& r) { return py::make_tuple(r.timestamp, r.channel, to_bytes(r.data)); }

py::dict damage_dict(const runtime::LogDamage& d) {
  py::dict out;
  out["damaged"] = d.damaged();
  out["bad_events"] = d.bad_events;
  out["skipped_bytes"] = d.skipped_bytes;
  out["missing_event_numbers"] = d.missing_event_numbers;
  out["truncated_tail_bytes"] = d.truncated_tail_bytes;
  py::list problems;
  for (const auto& p : d.first_problems) problems.append(p);
  out["first_problems"] = problems;
  out["summary"] = d.summary();
  return out;
}

// The reader skips what is corrupt and goes on; the caller hears of it as a RuntimeWarning naming the log (the
// events skipped are not in what it got), and reads the details from LogReader.damage.
void warn_damage(const std::string& path, const runtime::LogDamage& d) {
  const std::string s = d.summary();
  if (s.empty()) return;
  const std::string message = path + ": " + s;
  if (PyErr_WarnEx(PyExc_RuntimeWarning, message.c_str(), 1) != 0) throw py::error_already_set();
}

class PyLogReader {
 public:
  explicit PyLogReader(const std::string& path) : path_(path), reader_(path) {}
  py::tuple next() {
    auto r = reader_.next();
    if (!r) {
      if (!warned_) warned_ = true, warn_damage(path_, reader_.damage());
      throw py::stop_iteration();
    }
    return record_tuple(*r);
  }
  py::dict damage() const { return damage_dict(reader_.damage()); }

 private:
  std::string path_;
  runtime::LogReader reader_;
  bool warned_ = false;
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
    if (!writer_) return;
    writer_->flush();
    written_at_close_ = writer_->events_written();
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

}  // namespace

void register_logs(py::module_& m) {
  py::class_<PyLogReader>(m, "LogReader",
                          "Iterates over an LCM log: (timestamp_us, channel, data) per event.  Corrupt events are "
                          "skipped (the reader resynchronises on the next one); at the end a RuntimeWarning names the "
                          "log and what was skipped, and `damage` has the counts.")
      .def(py::init<const std::string&>(), py::arg("path"))
      .def(
          "__iter__", [](PyLogReader& r) -> PyLogReader& { return r; }, py::return_value_policy::reference_internal)
      .def("__next__", &PyLogReader::next)
      .def_property_readonly("damage", &PyLogReader::damage,
                             "What was skipped so far: damaged, bad_events, skipped_bytes, missing_event_numbers, "
                             "truncated_tail_bytes, first_problems ('byte OFFSET: what'), summary.");
  m.def(
      "read_log",
      [](const std::string& path) {
        py::list l;
        runtime::LogDamage damage;
        for (const auto& r : runtime::LogReader::read_all(path, &damage)) l.append(record_tuple(r));
        warn_damage(path, damage);
        return l;
      },
      py::arg("path"),
      "Every good event of an LCM log as (timestamp_us, channel, data), in file order; a RuntimeWarning "
      "names the log and what was skipped when it is damaged or its last event truncated.");
  py::class_<PyLogWriter>(m, "LogWriter", "Writes an LCM log (lcm-logger's format); a context manager.")
      .def(py::init<const std::string&>(), py::arg("path"))
      .def("write", &PyLogWriter::write, py::arg("timestamp"), py::arg("channel"), py::arg("data"))
      .def("write_message", &PyLogWriter::write_message, py::arg("timestamp"), py::arg("channel"), py::arg("type"),
           py::arg("message"), "Encodes the dict as `type` and writes it.")
      .def("flush", &PyLogWriter::flush)
      .def("close", &PyLogWriter::close)
      .def_property_readonly("events_written", &PyLogWriter::events_written)
      .def(
          "__enter__", [](PyLogWriter& w) -> PyLogWriter& { return w; }, py::return_value_policy::reference_internal)
      .def("__exit__", [](PyLogWriter& w, py::args) { w.close(); });
}

}  // namespace sextant::python
