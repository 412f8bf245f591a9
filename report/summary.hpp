#pragma once
// An ordered list of named scalars: the summary a tool prints with --json, kept as values so the same keys reach
// JSON (`sextant optimize --json`, `sextant eval --json`) and Python dicts (python/) from one place.
#include "report/json_writer.hpp"

#include <cstdint>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace sextant::tools {

using SummaryValue = std::variant<bool, int64_t, double, std::string>;

class Summary {
 public:
  Summary& add(const std::string& key, bool v) { return put(key, v); }
  Summary& add(const std::string& key, int v) { return put(key, static_cast<int64_t>(v)); }
  Summary& add(const std::string& key, int64_t v) { return put(key, v); }
  Summary& add(const std::string& key, size_t v) { return put(key, static_cast<int64_t>(v)); }
  Summary& add(const std::string& key, double v) { return put(key, v); }
  Summary& add(const std::string& key, const std::string& v) { return put(key, v); }
  Summary& add(const std::string& key, const char* v) { return put(key, std::string(v)); }

  const std::vector<std::pair<std::string, SummaryValue>>& entries() const { return entries_; }

  /// Writes the entries as the fields of the current JSON object (non-finite doubles become null).
  void write_fields(JsonWriter& j) const {
    for (const auto& [k, v] : entries_) {
      j.key(k);
      std::visit([&j](const auto& x) { j.value(x); }, v);
    }
  }

  /// `{...}` with these entries, as the tools print it.
  std::string json() const {
    JsonWriter j;
    j.begin_object();
    write_fields(j);
    j.end_object();
    return j.str();
  }

 private:
  Summary& put(const std::string& key, SummaryValue v) {
    entries_.emplace_back(key, std::move(v));
    return *this;
  }
  std::vector<std::pair<std::string, SummaryValue>> entries_;
};

}  // namespace sextant::tools
