#pragma once
// Every sextant LCM message as a Python dict and back.  The per-message functions are generated from the .lcm files
// (python/generate_message_dicts.py); this header holds what they share: strict readers that name the field of
// every error ("odometry_t.covariance[3]: expected a number, got str"), and the table of message types by name and
// by fingerprint (the 8 bytes every LCM message starts with), so bytes from a log or the bus decode without being
// told their type.
#include <pybind11/pybind11.h>

#include <cstdint>
#include <initializer_list>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace sextant::python {

namespace py = pybind11;

/// One field of a message as the .lcm file declares it: `type` is an LCM type ("int64_t", "double", "string",
/// "boolean", "byte", or a message type such as "sextant.channel_status_t"), `dim` the array size ("" for a scalar,
/// "3", or the name of the field holding the length).
struct FieldInfo {
  const char* name;
  const char* type;
  const char* dim;
};

struct MessageType {
  std::string name;  // "odometry_t"
  std::vector<FieldInfo> fields;
  int64_t fingerprint;                                // lcm-gen's getHash()
  py::dict (*decode)(const void* data, size_t size);  // throws std::invalid_argument on bad bytes
  std::vector<uint8_t> (*encode)(py::handle dict);    // throws std::invalid_argument naming the field
};

/// Every message type of lcmtypes/sextant (generated).
const std::vector<MessageType>& message_types();

inline bool has(const py::dict& d, const char* key) { return d.contains(key) && !d[key].is_none(); }

inline std::string type_name(py::handle obj) { return py::str(py::type::handle_of(obj).attr("__name__")); }

inline py::dict as_dict(py::handle obj, const std::string& where) {
  if (!py::isinstance<py::dict>(obj)) throw std::invalid_argument(where + ": expected a dict, got " + type_name(obj));
  return py::reinterpret_borrow<py::dict>(obj);
}

/// A list or tuple; `size` >= 0 is the required length of a fixed-size array.
inline py::list as_list(py::handle obj, const std::string& where, long size) {
  if (!py::isinstance<py::list>(obj) && !py::isinstance<py::tuple>(obj))
    throw std::invalid_argument(where + ": expected a list, got " + type_name(obj));
  py::list l(py::reinterpret_borrow<py::object>(obj));
  if (size >= 0 && static_cast<long>(l.size()) != size)
    throw std::invalid_argument(where + ": expected " + std::to_string(size) + " values, got " +
                                std::to_string(l.size()));
  return l;
}

inline void reject_unknown_keys(const py::dict& d, std::initializer_list<const char*> known, const std::string& where) {
  for (const auto& item : d) {
    const std::string key = py::isinstance<py::str>(item.first) ? py::cast<std::string>(item.first) : std::string("?");
    bool found = false;
    for (const char* k : known) found = found || key == k;
    if (!found) {
      std::string list;
      for (const char* k : known) list += (list.empty() ? "" : ", ") + std::string(k);
      throw std::invalid_argument(where + ": unknown field '" + key + "' (fields: " + list + ")");
    }
  }
}

inline double read_number(py::handle obj, const std::string& where) {
  if (py::isinstance<py::bool_>(obj) || !(py::isinstance<py::float_>(obj) || py::isinstance<py::int_>(obj)))
    throw std::invalid_argument(where + ": expected a number, got " + type_name(obj));
  return py::cast<double>(obj);
}

template <class T>
T read_integer(py::handle obj, const std::string& where) {
  if (py::isinstance<py::bool_>(obj) || !py::isinstance<py::int_>(obj))
    throw std::invalid_argument(where + ": expected an integer, got " + type_name(obj));
  const py::int_ lo(std::numeric_limits<T>::min()), hi(std::numeric_limits<T>::max());
  if (obj < lo || obj > hi)
    throw std::invalid_argument(where + ": " + py::cast<std::string>(py::str(obj)) + " is out of range [" +
                                std::to_string(std::numeric_limits<T>::min()) + ", " +
                                std::to_string(std::numeric_limits<T>::max()) + "]");
  return py::cast<T>(obj);
}

inline int8_t read_bool(py::handle obj, const std::string& where) {
  if (!py::isinstance<py::bool_>(obj))
    throw std::invalid_argument(where + ": expected True or False, got " + type_name(obj));
  return py::cast<bool>(obj) ? 1 : 0;
}

inline std::string read_string(py::handle obj, const std::string& where) {
  if (!py::isinstance<py::str>(obj)) throw std::invalid_argument(where + ": expected a str, got " + type_name(obj));
  return py::cast<std::string>(obj);
}

/// The length of the arrays sized by `length_key`: all of them must agree, and with `length_key` when the dict gives it.
inline size_t array_length(const py::dict& d, const char* length_key,
                           std::initializer_list<std::pair<const char*, size_t>> arrays, const std::string& where) {
  const auto first = *arrays.begin();
  for (const auto& [name, n] : arrays)
    if (n != first.second)
      throw std::invalid_argument(where + ": " + first.first + " has " + std::to_string(first.second) +
                                  " entries but " + name + " has " + std::to_string(n) + " (both are sized by " +
                                  length_key + ")");
  if (has(d, length_key)) {
    const auto given = read_integer<int64_t>(d[length_key], where + "." + length_key);
    if (given != static_cast<int64_t>(first.second))
      throw std::invalid_argument(where + "." + length_key + ": " + std::to_string(given) + " but " + first.first +
                                  " has " + std::to_string(first.second) + " entries");
  }
  if (first.second > static_cast<size_t>(std::numeric_limits<int32_t>::max()))
    throw std::invalid_argument(where + "." + first.first + ": too many entries");
  return first.second;
}

}  // namespace sextant::python
