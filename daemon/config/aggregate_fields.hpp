#pragma once
// The fields of plain aggregates (the config structs), without a list in each: the number of fields is found by
// brace-initializing with as many convertible placeholders as the struct takes, and the fields are reached by
// structured bindings (up to 40 per struct).  Used to fingerprint a parsed config by its values (FieldHash, below;
// the state directory refuses another config's state) and by the tests to compare configs field by field.
#include <array>
#include <cstddef>
#include <cstdint>
#include <tuple>
#include <map>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace sextant::config {

struct AnyField {
  template <class T>
  operator T() const;  // never defined: only the initialization's well-formedness is asked for
};

template <class T, class... A>
constexpr bool brace_constructible = requires {
  T{std::declval<A>()...};
};

template <class T, size_t... I>
constexpr bool takes_fields(std::index_sequence<I...>) {
  return brace_constructible<T, decltype((void)I, AnyField{})...>;
}

template <class T, size_t N = 0>
constexpr size_t field_count() {
  if constexpr (N > 40)
    return 0;
  else if constexpr (takes_fields<T>(std::make_index_sequence<N + 1>{}))
    return field_count<T, N + 1>();
  else
    return N;
}

template <class T>
struct is_std_vector : std::false_type {};
template <class T, class A>
struct is_std_vector<std::vector<T, A>> : std::true_type {};
template <class T>
struct is_std_map : std::false_type {};
template <class K, class V, class C, class A>
struct is_std_map<std::map<K, V, C, A>> : std::true_type {};
template <class T>
struct is_std_optional : std::false_type {};
template <class T>
struct is_std_optional<std::optional<T>> : std::true_type {};
template <class T>
struct is_std_array : std::false_type {};
template <class T, size_t N>
struct is_std_array<std::array<T, N>> : std::true_type {};

// One case of fields_of: an aggregate of `count` fields, bound by a structured binding to the names given and tied
// (structured bindings take a fixed number of names, so each count is a case of its own).
#define SEXTANT_FIELDS_CASE(count, ...) \
  else if constexpr (n == count) {      \
    auto& [__VA_ARGS__] = t;            \
    return std::tie(__VA_ARGS__);       \
  }

/// The fields of `t` as a tuple of references.
template <class T>
auto fields_of(T& t) {
  constexpr size_t n = field_count<std::remove_const_t<T>>();
  static_assert(n >= 1 && n <= 40, "fields_of: not an aggregate of 1 to 40 fields");
  if constexpr (n == 0) return std::tuple<>();
  SEXTANT_FIELDS_CASE(1, f0)
  SEXTANT_FIELDS_CASE(2, f0, f1)
  SEXTANT_FIELDS_CASE(3, f0, f1, f2)
  SEXTANT_FIELDS_CASE(4, f0, f1, f2, f3)
  SEXTANT_FIELDS_CASE(5, f0, f1, f2, f3, f4)
  SEXTANT_FIELDS_CASE(6, f0, f1, f2, f3, f4, f5)
  SEXTANT_FIELDS_CASE(7, f0, f1, f2, f3, f4, f5, f6)
  SEXTANT_FIELDS_CASE(8, f0, f1, f2, f3, f4, f5, f6, f7)
  SEXTANT_FIELDS_CASE(9, f0, f1, f2, f3, f4, f5, f6, f7, f8)
  SEXTANT_FIELDS_CASE(10, f0, f1, f2, f3, f4, f5, f6, f7, f8, f9)
  SEXTANT_FIELDS_CASE(11, f0, f1, f2, f3, f4, f5, f6, f7, f8, f9, f10)
  SEXTANT_FIELDS_CASE(12, f0, f1, f2, f3, f4, f5, f6, f7, f8, f9, f10, f11)
  SEXTANT_FIELDS_CASE(13, f0, f1, f2, f3, f4, f5, f6, f7, f8, f9, f10, f11, f12)
  SEXTANT_FIELDS_CASE(14, f0, f1, f2, f3, f4, f5, f6, f7, f8, f9, f10, f11, f12, f13)
  SEXTANT_FIELDS_CASE(15, f0, f1, f2, f3, f4, f5, f6, f7, f8, f9, f10, f11, f12, f13, f14)
  SEXTANT_FIELDS_CASE(16, f0, f1, f2, f3, f4, f5, f6, f7, f8, f9, f10, f11, f12, f13, f14, f15)
  SEXTANT_FIELDS_CASE(17, f0, f1, f2, f3, f4, f5, f6, f7, f8, f9, f10, f11, f12, f13, f14, f15, f16)
  SEXTANT_FIELDS_CASE(18, f0, f1, f2, f3, f4, f5, f6, f7, f8, f9, f10, f11, f12, f13, f14, f15, f16, f17)
  SEXTANT_FIELDS_CASE(19, f0, f1, f2, f3, f4, f5, f6, f7, f8, f9, f10, f11, f12, f13, f14, f15, f16, f17, f18)
  SEXTANT_FIELDS_CASE(20, f0, f1, f2, f3, f4, f5, f6, f7, f8, f9, f10, f11, f12, f13, f14, f15, f16, f17, f18, f19)
  SEXTANT_FIELDS_CASE(21, f0, f1, f2, f3, f4, f5, f6, f7, f8, f9, f10, f11, f12, f13, f14, f15, f16, f17, f18, f19, f20)
  SEXTANT_FIELDS_CASE(22, f0, f1, f2, f3, f4, f5, f6, f7, f8, f9, f10, f11, f12, f13, f14, f15, f16, f17, f18, f19, f20,
                      f21)
  SEXTANT_FIELDS_CASE(23, f0, f1, f2, f3, f4, f5, f6, f7, f8, f9, f10, f11, f12, f13, f14, f15, f16, f17, f18, f19, f20,
                      f21, f22)
  SEXTANT_FIELDS_CASE(24, f0, f1, f2, f3, f4, f5, f6, f7, f8, f9, f10, f11, f12, f13, f14, f15, f16, f17, f18, f19, f20,
                      f21, f22, f23)
  SEXTANT_FIELDS_CASE(25, f0, f1, f2, f3, f4, f5, f6, f7, f8, f9, f10, f11, f12, f13, f14, f15, f16, f17, f18, f19, f20,
                      f21, f22, f23, f24)
  SEXTANT_FIELDS_CASE(26, f0, f1, f2, f3, f4, f5, f6, f7, f8, f9, f10, f11, f12, f13, f14, f15, f16, f17, f18, f19, f20,
                      f21, f22, f23, f24, f25)
  SEXTANT_FIELDS_CASE(27, f0, f1, f2, f3, f4, f5, f6, f7, f8, f9, f10, f11, f12, f13, f14, f15, f16, f17, f18, f19, f20,
                      f21, f22, f23, f24, f25, f26)
  SEXTANT_FIELDS_CASE(28, f0, f1, f2, f3, f4, f5, f6, f7, f8, f9, f10, f11, f12, f13, f14, f15, f16, f17, f18, f19, f20,
                      f21, f22, f23, f24, f25, f26, f27)
  SEXTANT_FIELDS_CASE(29, f0, f1, f2, f3, f4, f5, f6, f7, f8, f9, f10, f11, f12, f13, f14, f15, f16, f17, f18, f19, f20,
                      f21, f22, f23, f24, f25, f26, f27, f28)
  SEXTANT_FIELDS_CASE(30, f0, f1, f2, f3, f4, f5, f6, f7, f8, f9, f10, f11, f12, f13, f14, f15, f16, f17, f18, f19, f20,
                      f21, f22, f23, f24, f25, f26, f27, f28, f29)
  SEXTANT_FIELDS_CASE(31, f0, f1, f2, f3, f4, f5, f6, f7, f8, f9, f10, f11, f12, f13, f14, f15, f16, f17, f18, f19, f20,
                      f21, f22, f23, f24, f25, f26, f27, f28, f29, f30)
  SEXTANT_FIELDS_CASE(32, f0, f1, f2, f3, f4, f5, f6, f7, f8, f9, f10, f11, f12, f13, f14, f15, f16, f17, f18, f19, f20,
                      f21, f22, f23, f24, f25, f26, f27, f28, f29, f30, f31)
  SEXTANT_FIELDS_CASE(33, f0, f1, f2, f3, f4, f5, f6, f7, f8, f9, f10, f11, f12, f13, f14, f15, f16, f17, f18, f19, f20,
                      f21, f22, f23, f24, f25, f26, f27, f28, f29, f30, f31, f32)
  SEXTANT_FIELDS_CASE(34, f0, f1, f2, f3, f4, f5, f6, f7, f8, f9, f10, f11, f12, f13, f14, f15, f16, f17, f18, f19, f20,
                      f21, f22, f23, f24, f25, f26, f27, f28, f29, f30, f31, f32, f33)
  SEXTANT_FIELDS_CASE(35, f0, f1, f2, f3, f4, f5, f6, f7, f8, f9, f10, f11, f12, f13, f14, f15, f16, f17, f18, f19, f20,
                      f21, f22, f23, f24, f25, f26, f27, f28, f29, f30, f31, f32, f33, f34)
  SEXTANT_FIELDS_CASE(36, f0, f1, f2, f3, f4, f5, f6, f7, f8, f9, f10, f11, f12, f13, f14, f15, f16, f17, f18, f19, f20,
                      f21, f22, f23, f24, f25, f26, f27, f28, f29, f30, f31, f32, f33, f34, f35)
  SEXTANT_FIELDS_CASE(37, f0, f1, f2, f3, f4, f5, f6, f7, f8, f9, f10, f11, f12, f13, f14, f15, f16, f17, f18, f19, f20,
                      f21, f22, f23, f24, f25, f26, f27, f28, f29, f30, f31, f32, f33, f34, f35, f36)
  SEXTANT_FIELDS_CASE(38, f0, f1, f2, f3, f4, f5, f6, f7, f8, f9, f10, f11, f12, f13, f14, f15, f16, f17, f18, f19, f20,
                      f21, f22, f23, f24, f25, f26, f27, f28, f29, f30, f31, f32, f33, f34, f35, f36, f37)
  SEXTANT_FIELDS_CASE(39, f0, f1, f2, f3, f4, f5, f6, f7, f8, f9, f10, f11, f12, f13, f14, f15, f16, f17, f18, f19, f20,
                      f21, f22, f23, f24, f25, f26, f27, f28, f29, f30, f31, f32, f33, f34, f35, f36, f37, f38)
  SEXTANT_FIELDS_CASE(40, f0, f1, f2, f3, f4, f5, f6, f7, f8, f9, f10, f11, f12, f13, f14, f15, f16, f17, f18, f19, f20,
                      f21, f22, f23, f24, f25, f26, f27, f28, f29, f30, f31, f32, f33, f34, f35, f36, f37, f38, f39)
}

#undef SEXTANT_FIELDS_CASE

/// An aggregate with a base class cannot be decomposed by structured bindings: such a type lists its parts (the base
/// first, then its own fields) in a specialization `static auto of(const T& t) { return std::tie(...); }`; their
/// number is checked against the number of fields brace-initialization finds, so a field added and not listed fails
/// to compile.
template <class T>
struct aggregate_parts;
template <class T>
concept has_aggregate_parts = requires(const T& t) {
  aggregate_parts<T>::of(t);
};

/// The parts of an aggregate, as a tuple of references: aggregate_parts<T>::of when T lists them, else its fields.
template <class T>
auto parts_of(const T& x) {
  if constexpr (has_aggregate_parts<T>) {
    const auto parts = aggregate_parts<T>::of(x);
    static_assert(std::tuple_size_v<std::remove_const_t<decltype(parts)>> == field_count<T>(),
                  "aggregate_parts: a field is not listed");
    return parts;
  } else {
    return fields_of(x);
  }
}

/// FNV-1a over a canonical serialization of `x`'s values, field by field (nested aggregates, vectors, arrays, maps,
/// optionals; arithmetic values and enums by their bytes, strings by length and bytes; pointers, run-time handles,
/// not at all): two values equal field by field hash the same, whatever text they were parsed from.
class FieldHash {
 public:
  template <class T>
  FieldHash& add(const T& x) {
    if constexpr (std::is_same_v<T, std::string>) {
      add(static_cast<uint64_t>(x.size()));
      bytes(x.data(), x.size());
    } else if constexpr (is_std_vector<T>::value || is_std_array<T>::value) {
      add(static_cast<uint64_t>(x.size()));
      for (const auto& e : x) add(e);
    } else if constexpr (is_std_map<T>::value) {
      add(static_cast<uint64_t>(x.size()));
      for (const auto& [k, v] : x) add(k).add(v);
    } else if constexpr (is_std_optional<T>::value) {
      add(x.has_value());
      if (x) add(*x);
    } else if constexpr (std::is_enum_v<T>) {
      add(static_cast<int64_t>(x));
    } else if constexpr (std::is_same_v<T, bool>) {
      const unsigned char b = x ? 1 : 0;
      bytes(&b, 1);
    } else if constexpr (std::is_floating_point_v<T>) {
      const double d = x == 0 ? 0.0 : static_cast<double>(x);  // -0 and 0 are one value
      bytes(&d, sizeof d);
    } else if constexpr (std::is_integral_v<T>) {
      const auto v = static_cast<int64_t>(x);
      bytes(&v, sizeof v);
    } else if constexpr (std::is_pointer_v<T>) {
      // A handle its owner sets at run time (graph::IncrementalOptions::interrupt), never a parsed value: no part of
      // the fingerprint.
    } else if constexpr (std::is_aggregate_v<T>) {
      const auto parts = parts_of(x);
      add(static_cast<uint64_t>(std::tuple_size_v<std::remove_const_t<decltype(parts)>>));
      std::apply([this](const auto&... p) { (add(p), ...); }, parts);
    } else {
      static_assert(std::is_aggregate_v<T>, "FieldHash: a field of a type it cannot serialize");
    }
    return *this;
  }
  uint64_t value() const { return h_; }

 private:
  void bytes(const void* data, size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < n; ++i) h_ = (h_ ^ p[i]) * 1099511628211ull;
  }
  uint64_t h_ = 1469598103934665603ull;
};

}  // namespace sextant::config
