// The `sextant` module's messages: every sextant message type as a dict and back (message_dicts.hpp), decoding by
// fingerprint, and the daemon's own validation of input messages (daemon/runtime/codec.hpp).
#include "python/module_parts.hpp"

#include "daemon/runtime/codec.hpp"

#include <pybind11/stl.h>

#include <map>
#include <optional>

namespace sextant::python {

const MessageType& type_by_name(const std::string& name) {
  for (const auto& t : message_types())
    if (t.name == name) return t;
  std::string list;
  for (const auto& t : message_types()) list += (list.empty() ? "" : ", ") + t.name;
  throw py::value_error("unknown message type '" + name + "' (types: " + list + ")");
}

const MessageType* type_of(const void* data, size_t size) {
  if (size < 8) return nullptr;
  const auto* b = static_cast<const uint8_t*>(data);
  uint64_t h = 0;
  for (int i = 0; i < 8; ++i) h = (h << 8) | b[i];
  for (const auto& t : message_types())
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

namespace {

py::dict decode(const py::bytes& data, const std::optional<std::string>& type) {
  const auto v = bytes_view(data);
  if (type) return type_by_name(*type).decode(v.data(), v.size());
  const MessageType* t = type_of(v.data(), v.size());
  if (t == nullptr)
    throw py::value_error("not a sextant message: its fingerprint matches none of the " +
                          std::to_string(message_types().size()) + " types (pass type= to decode anyway)");
  return t->decode(v.data(), v.size());
}

py::object message_type_of(const py::bytes& data) {
  const auto v = bytes_view(data);
  const MessageType* t = type_of(v.data(), v.size());
  return t ? py::object(py::str(t->name)) : py::object(py::none());
}

py::bytes encode(const std::string& type, const py::handle& message) {
  return to_bytes(type_by_name(type).encode(message));
}

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

}  // namespace

void register_messages(py::module_& m) {
  m.def(
      "message_types",
      [] {
        std::vector<std::string> names;
        for (const auto& t : message_types()) names.push_back(t.name);
        return names;
      },
      "Names of every sextant message type (lcmtypes/sextant/*.lcm).");
  m.def(
      "message_fields",
      [](const std::string& type) {
        py::list l;
        for (const auto& f : type_by_name(type).fields) l.append(py::make_tuple(f.name, f.type, f.dim));
        return l;
      },
      py::arg("type"),
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
}

}  // namespace sextant::python
