#pragma once
// One-line, human-readable summaries of sextant messages, recognised by their LCM fingerprint (for
// `sextant listen` and the demo's live view).
#include <cstddef>
#include <string>

namespace sextant::tools {

/// "<type> <summary>" for a sextant message, or "unknown type (N bytes)" for anything else.
std::string describe_message(const void* data, size_t size);

}  // namespace sextant::tools
