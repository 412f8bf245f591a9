#pragma once
// Field-by-field equality of plain aggregates (the config structs), without an operator== in each (the fields are
// found by daemon/config/aggregate_fields.hpp): the comparison recurses into nested aggregates, std::vector,
// std::map, std::optional and std::array; other fields are compared with ==.  A difference is reported as the path
// of field indices to it ("3.12.0": field 12 of field 3, element 0).
#include "daemon/config/aggregate_fields.hpp"

#include <string>

namespace sextant::testing {

using config::aggregate_parts;
using config::field_count;
using config::fields_of;
using config::has_aggregate_parts;
using config::is_std_array;
using config::is_std_map;
using config::is_std_optional;
using config::is_std_vector;

/// Empty when `a` and `b` are equal field by field; else the path of the first difference.
template <class T>
std::string first_difference(const T& a, const T& b, const std::string& path = "") {
  const auto at = [&](auto i) { return path.empty() ? std::to_string(i) : path + "." + std::to_string(i); };
  if constexpr (is_std_vector<T>::value || is_std_array<T>::value) {
    if (a.size() != b.size()) return path + " (size)";
    for (size_t i = 0; i < a.size(); ++i)
      if (auto d = first_difference(a[i], b[i], at(i)); !d.empty()) return d;
    return "";
  } else if constexpr (is_std_map<T>::value) {
    if (a.size() != b.size()) return path + " (size)";
    auto j = b.begin();
    size_t i = 0;
    for (auto it = a.begin(); it != a.end(); ++it, ++j, ++i) {
      if (!(it->first == j->first)) return at(i) + " (key)";
      if (auto d = first_difference(it->second, j->second, at(i)); !d.empty()) return d;
    }
    return "";
  } else if constexpr (is_std_optional<T>::value) {
    if (a.has_value() != b.has_value()) return path + " (set or not)";
    return a ? first_difference(*a, *b, path) : "";
  } else if constexpr (std::is_aggregate_v<T>) {
    const auto fa = [](const T& x) {
      if constexpr (has_aggregate_parts<T>)
        return aggregate_parts<T>::of(x);
      else
        return fields_of(x);
    }(a);
    const auto fb = [](const T& x) {
      if constexpr (has_aggregate_parts<T>)
        return aggregate_parts<T>::of(x);
      else
        return fields_of(x);
    }(b);
    static_assert(std::tuple_size_v<std::remove_const_t<decltype(fa)>> == field_count<T>(),
                  "aggregate_parts: a field is not listed");
    std::string d;
    [&]<size_t... I>(std::index_sequence<I...>) {
      ((d.empty() ? (void)(d = first_difference(std::get<I>(fa), std::get<I>(fb), at(I))) : (void)0), ...);
    }
    (std::make_index_sequence<std::tuple_size_v<decltype(fa)>>{});
    return d;
  } else {
    return a == b ? "" : (path.empty() ? "(value)" : path);
  }
}

}  // namespace sextant::testing
