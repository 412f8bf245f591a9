#include "daemon/config/config_reader.hpp"

#include <sstream>

namespace sextant::config {

Section::Section(YAML::Node node, std::string path, std::string file)
    : node_(std::move(node)), path_(std::move(path)), file_(std::move(file)) {
  if (node_.IsDefined() && !node_.IsNull() && !node_.IsMap())
    throw error_at(node_, "'" + (path_.empty() ? std::string("<top>") : path_) + "': expected a mapping of keys");
}

Section Section::child(const std::string& key) {
  known_.insert(key);
  return Section(lookup(key), qualified(key), file_);
}

YAML::Node Section::lookup(const std::string& key) const {
  if (!node_.IsMap()) return YAML::Node(YAML::NodeType::Undefined);
  const YAML::Node& map = node_;
  const YAML::Node found = map[key];
  // A const lookup of a missing key gives an invalid node that throws on most queries: hand out a plain undefined one.
  return found.IsDefined() ? found : YAML::Node(YAML::NodeType::Undefined);
}

void Section::check_plain_key(const YAML::Node& key) const {
  if (!key.IsScalar())
    throw error_at(key, "'" + (path_.empty() ? std::string("<top>") : path_) + "': a key must be a plain name, got " +
                            scalar_text(key));
}

std::vector<YAML::Node> Section::keys() const {
  std::vector<YAML::Node> out;
  if (!node_.IsMap()) return out;
  for (const auto& kv : node_) {
    check_plain_key(kv.first);
    out.push_back(kv.first);
  }
  return out;
}

void Section::reject_unknown_keys() const {
  if (!node_.IsMap()) return;
  for (const auto& kv : node_) {
    check_plain_key(kv.first);
    const auto key = kv.first.Scalar();
    if (known_.count(key)) continue;
    std::ostringstream known;
    for (const auto& k : known_) known << (known.tellp() > 0 ? ", " : "") << k;
    throw error_at(kv.first, "unknown key '" + qualified(key) + "' (known keys here: " + known.str() + ")");
  }
}

ConfigError Section::error_at(const YAML::Node& node, const std::string& message) const {
  std::ostringstream s;
  s << file_;
  if (node.IsDefined() && node.Mark().line >= 0) s << ":" << node.Mark().line + 1 << ":" << node.Mark().column + 1;
  s << ": " << message;
  return ConfigError(s.str());
}

std::string Section::scalar_text(const YAML::Node& v) {
  if (v.IsScalar()) return v.Scalar();
  if (v.IsSequence()) return "a list";
  if (v.IsMap()) return "a mapping";
  return "nothing";
}

Check<double> positive() {
  return [](const double& v) -> std::optional<std::string> {
    if (v > 0 && std::isfinite(v)) return std::nullopt;
    return "must be a positive number, got " + std::to_string(v);
  };
}
Check<double> non_negative() {
  return [](const double& v) -> std::optional<std::string> {
    if (v >= 0 && std::isfinite(v)) return std::nullopt;
    return "must be >= 0, got " + std::to_string(v);
  };
}
Check<double> in_range(double lo, double hi) {
  return [lo, hi](const double& v) -> std::optional<std::string> {
    if (v >= lo && v <= hi) return std::nullopt;
    std::ostringstream s;
    s << "must be in [" << lo << ", " << hi << "], got " << v;
    return s.str();
  };
}
Check<int> positive_int() {
  return [](const int& v) -> std::optional<std::string> {
    if (v > 0) return std::nullopt;
    return "must be a positive integer, got " + std::to_string(v);
  };
}
Check<int> int_in_range(int lo, int hi) {
  return [lo, hi](const int& v) -> std::optional<std::string> {
    if (v >= lo && v <= hi) return std::nullopt;
    return "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " + std::to_string(v);
  };
}
Check<std::string> one_of(std::vector<std::string> allowed) {
  return [allowed](const std::string& v) -> std::optional<std::string> {
    std::string list;
    for (const auto& a : allowed) {
      if (a == v) return std::nullopt;
      list += (list.empty() ? "" : ", ") + a;
    }
    return "must be one of: " + list + "; got '" + v + "'";
  };
}

}  // namespace sextant::config
