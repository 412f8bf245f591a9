#pragma once
// What the files of the sextant Python module share: message types by name and by fingerprint, bytes conversions,
// and the functions that register each part of the module (messages.cpp, logs.cpp, bus.cpp, solvers.cpp).
#include "python/message_dicts.hpp"

#include <string>
#include <string_view>
#include <vector>

namespace sextant::python {

/// The message type of this name; ValueError listing the types when there is none.
const MessageType& type_by_name(const std::string& name);
/// The type whose fingerprint the bytes start with (LCM's 8-byte big-endian hash), or nullptr.
const MessageType* type_of(const void* data, size_t size);
/// The bytes of a Python bytes object, without copying.
std::string_view bytes_view(const py::bytes& b);
py::bytes to_bytes(const std::vector<uint8_t>& v);

void register_messages(py::module_& m);  // message_types, message_fields, decode, message_type, encode, validate
void register_logs(py::module_& m);      // LogReader, read_log, LogWriter
void register_bus(py::module_& m);       // Bus
void register_solvers(py::module_& m);   // optimize, eval

}  // namespace sextant::python
