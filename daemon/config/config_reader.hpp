#pragma once
// A YAML section reader that validates as it reads and names the place of every error as file:line:column.
// Unknown keys are errors (a misspelt key must never be silently ignored).
#include <yaml-cpp/yaml.h>

#include <functional>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace sextant::config {

/// A configuration error; what() is "FILE:LINE:COLUMN: message".
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Returns an error message when a value is invalid, nullopt when it is fine.
template <class T>
using Check = std::function<std::optional<std::string>(const T&)>;

class Section {
 public:
  /// `node` may be null/undefined (a missing section: every read keeps its default).
  Section(YAML::Node node, std::string path, std::string file);

  /// Reads `key` into `out` if present (keeps the default otherwise); throws ConfigError on a value of the wrong
  /// type or one that `check` refuses.
  template <class T>
  void get(const std::string& key, T& out, const Check<T>& check = {}) {
    known_.insert(key);
    if (!node_.IsMap()) return;
    const YAML::Node v = lookup(key);
    if (!v.IsDefined() || v.IsNull()) return;
    T value;
    try {
      value = v.as<T>();
    } catch (const YAML::Exception&) {
      throw error_at(v, "'" + qualified(key) + "': expected " + type_name<T>() + ", got '" + scalar_text(v) + "'");
    }
    if (check) {
      if (auto why = check(value)) throw error_at(v, "'" + qualified(key) + "': " + *why);
    }
    out = value;
  }

  /// Reads `key` as a name and turns it into a kind with `parse` (a function of the kind's own header that throws
  /// std::invalid_argument for a name it does not know, listing those it does), so that a kind is parsed once, here,
  /// and its spellings live beside its enum.  An unknown name is a ConfigError at the value's file:line:column.
  template <class T>
  void get_parsed(const std::string& key, T& out, T (*parse)(const std::string&)) {
    known_.insert(key);
    if (!node_.IsMap()) return;
    const YAML::Node v = lookup(key);
    if (!v.IsDefined() || v.IsNull()) return;
    std::string name;
    get(key, name);
    try {
      out = parse(name);
    } catch (const std::invalid_argument& e) {
      throw error_at(v, "'" + qualified(key) + "': " + e.what());
    }
  }

  /// A nested section (possibly missing).  Lookups never insert: a missing key is left missing.
  Section child(const std::string& key);

  /// The keys of this mapping in file order (none when the section is missing), each a plain name; a key that is not
  /// (null, a list, a mapping) throws ConfigError at its place.  For sections whose keys are names the user chooses
  /// (sources, mountings, markers): iterate these, then read each with child() or get().
  std::vector<YAML::Node> keys() const;

  /// Throws ConfigError naming the line of the first key that no `get`/`child` asked for.
  void reject_unknown_keys() const;

  /// Where an error about `key` points: the key's value if present, else this section.
  YAML::Node place_of(const std::string& key) const {
    const YAML::Node v = lookup(key);
    return v.IsDefined() ? v : node_;
  }

  /// An error at this section's own position.
  ConfigError error(const std::string& message) const { return error_at(node_, message); }
  ConfigError error_at(const YAML::Node& node, const std::string& message) const;

  const YAML::Node& node() const { return node_; }
  const std::string& path() const { return path_; }

 private:
  /// The value at `key`, or an undefined node.  Through a const node: yaml-cpp's non-const operator[] inserts a
  /// missing key, which would move the entries of a map that a caller is iterating over.
  YAML::Node lookup(const std::string& key) const;
  void check_plain_key(const YAML::Node& key) const;
  std::string qualified(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
  static std::string scalar_text(const YAML::Node& v);
  template <class T>
  static std::string type_name() {
    if constexpr (std::is_same_v<T, bool>)
      return "true or false";
    else if constexpr (std::is_integral_v<T>)
      return "an integer";
    else if constexpr (std::is_floating_point_v<T>)
      return "a number";
    else if constexpr (std::is_same_v<T, std::string>)
      return "a string";
    else
      return "a list";
  }

  YAML::Node node_;
  std::string path_;
  std::string file_;
  std::set<std::string> known_;
};

/// Common checks.
Check<double> positive();
Check<double> non_negative();
Check<double> in_range(double lo, double hi);
Check<int> positive_int();
Check<int> int_in_range(int lo, int hi);
Check<std::string> one_of(std::vector<std::string> allowed);

}  // namespace sextant::config
