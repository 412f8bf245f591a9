#pragma once
// Spelling tables of enumerated kinds: each enum that a user names in a config file or on the command line keeps its
// spellings in one constant table beside it, { {Kind::kA, "a"}, {Kind::kB, "b"} }, and these three functions read
// every table the same way, so a misspelt name is always the same clear error and never a silent default.
#include <cstddef>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace sextant {

/// The kind spelt `name`; throws std::invalid_argument("unknown WHAT 'name' (a, b or c)") for any other name.
template <class Kind, size_t N>
Kind kind_from_name(const std::pair<Kind, const char*> (&names)[N], const std::string& name, const char* what) {
  std::string list;
  for (size_t i = 0; i < N; ++i) {
    if (name == names[i].second) return names[i].first;
    list += std::string(i == 0 ? "" : i + 1 == N ? " or " : ", ") + names[i].second;
  }
  throw std::invalid_argument("unknown " + std::string(what) + " '" + name + "' (" + list + ")");
}

/// The spelling of `kind` ("?" for a value outside the table).
template <class Kind, size_t N>
const char* kind_name(const std::pair<Kind, const char*> (&names)[N], Kind kind) {
  for (const auto& [k, n] : names)
    if (k == kind) return n;
  return "?";
}

/// Every spelling, in the table's order (for command-line checks and help texts).
template <class Kind, size_t N>
std::vector<std::string> kind_names(const std::pair<Kind, const char*> (&names)[N]) {
  std::vector<std::string> out;
  for (const auto& [k, n] : names) out.emplace_back(n);
  return out;
}

}  // namespace sextant
