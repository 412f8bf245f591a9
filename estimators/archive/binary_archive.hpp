#pragma once
// A small binary archive for saving and restoring estimator state (the daemon's state directory, README "State
// directory").  One home for the encoding of every value a state holds:
//   - arithmetic values and enums: their bytes, little-endian (the only byte order sextant builds for);
//   - std::string: a 64-bit length, then the bytes;
//   - Eigen matrices and vectors (fixed or dynamic size): rows and columns (32 bits each), then the coefficients in
//     storage order; a quaternion: its four coefficients (x, y, z, w as Eigen stores them);
//   - std::vector, std::deque, std::map, std::pair, std::optional: a count (or a presence flag), then the elements;
//     a std::variant: the index of its alternative (32 bits), then the value;
//   - a class with members `void save(ArchiveWriter&) const` and `void load(ArchiveReader&)`: those (each stateful
//     class saves itself, next to its own code); or free functions save(ArchiveWriter&, const T&) and
//     load(ArchiveReader&, T&) found by argument-dependent lookup.
// Values are written exactly (doubles bit for bit), so a restored state continues as the saved one would have.
// The reader checks every length and count against the bytes left before allocating, and every fixed size against
// the type; a damaged or foreign archive throws ArchiveError naming the archive, the byte offset and what was being
// read, never reads past the end and never allocates more than the archive could hold.
#include <Eigen/Core>
#include <Eigen/Geometry>

#include <bit>
#include <cstdint>
#include <cstring>
#include <deque>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

namespace sextant::archive {

static_assert(std::endian::native == std::endian::little, "the archive format is little-endian");

class ArchiveError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class ArchiveWriter;
class ArchiveReader;

template <class T>
concept SavesItself = requires(const T& t, ArchiveWriter& w) {
  t.save(w);
};
template <class T>
concept LoadsItself = requires(T& t, ArchiveReader& r) {
  t.load(r);
};

template <class T>
struct is_eigen_matrix : std::false_type {};
template <class S, int R, int C, int O, int MR, int MC>
struct is_eigen_matrix<Eigen::Matrix<S, R, C, O, MR, MC>> : std::true_type {};

class ArchiveWriter {
 public:
  void raw(const void* p, size_t n) {
    const auto* b = static_cast<const char*>(p);
    data_.append(b, n);
  }

  template <class T>
  ArchiveWriter& operator()(const T& v) {
    if constexpr (std::is_arithmetic_v<T> || std::is_enum_v<T>) {
      raw(&v, sizeof v);
    } else if constexpr (std::is_same_v<T, std::string>) {
      (*this)(static_cast<uint64_t>(v.size()));
      raw(v.data(), v.size());
    } else if constexpr (is_eigen_matrix<T>::value) {
      (*this)(static_cast<uint32_t>(v.rows()));
      (*this)(static_cast<uint32_t>(v.cols()));
      raw(v.data(), sizeof(typename T::Scalar) * static_cast<size_t>(v.size()));
    } else if constexpr (std::is_same_v<T, Eigen::Quaterniond>) {
      raw(v.coeffs().data(), 4 * sizeof(double));
    } else if constexpr (SavesItself<T>) {
      v.save(*this);
    } else {
      save(*this, v);
    }
    return *this;
  }
  template <class A, class B>
  ArchiveWriter& operator()(const std::pair<A, B>& p) {
    return (*this)(p.first)(p.second);
  }
  template <class T>
  ArchiveWriter& operator()(const std::optional<T>& o) {
    (*this)(o.has_value());
    if (o) (*this)(*o);
    return *this;
  }
  template <class T, class A>
  ArchiveWriter& operator()(const std::vector<T, A>& v) {
    return sequence(v);
  }
  template <class T, class A>
  ArchiveWriter& operator()(const std::deque<T, A>& v) {
    return sequence(v);
  }
  template <class... T>
  ArchiveWriter& operator()(const std::variant<T...>& v) {
    (*this)(static_cast<uint32_t>(v.index()));
    std::visit([this](const auto& x) { (*this)(x); }, v);
    return *this;
  }
  template <class K, class V, class C, class A>
  ArchiveWriter& operator()(const std::map<K, V, C, A>& m) {
    (*this)(static_cast<uint64_t>(m.size()));
    for (const auto& [k, v] : m) (*this)(k)(v);
    return *this;
  }

  const std::string& data() const { return data_; }
  std::string take() { return std::move(data_); }

 private:
  template <class S>
  ArchiveWriter& sequence(const S& s) {
    (*this)(static_cast<uint64_t>(s.size()));
    for (const auto& x : s) (*this)(x);
    return *this;
  }
  std::string data_;
};

class ArchiveReader {
 public:
  /// `name` names the archive in errors (e.g. the state file's path and section).
  ArchiveReader(const void* data, size_t size, std::string name)
      : p_(static_cast<const unsigned char*>(data)), size_(size), name_(std::move(name)) {}

  void raw(void* out, size_t n, const char* what) {
    need(n, what);
    if (n == 0) return;  // an empty matrix's data() is null, which memcpy may not be given even for no bytes
    std::memcpy(out, p_ + at_, n);
    at_ += n;
  }

  template <class T>
  ArchiveReader& operator()(T& v) {
    if constexpr (std::is_same_v<T, bool>) {
      unsigned char b = 0;
      raw(&b, 1, "a flag");
      if (b > 1) fail("a flag that is neither 0 nor 1");
      v = b != 0;
    } else if constexpr (std::is_arithmetic_v<T> || std::is_enum_v<T>) {
      raw(&v, sizeof v, "a number");
    } else if constexpr (std::is_same_v<T, std::string>) {
      const uint64_t n = count(1, "a string");
      v.assign(reinterpret_cast<const char*>(p_ + at_), static_cast<size_t>(n));
      at_ += static_cast<size_t>(n);
    } else if constexpr (is_eigen_matrix<T>::value) {
      uint32_t rows = 0, cols = 0;
      (*this)(rows)(cols);
      if ((T::RowsAtCompileTime != Eigen::Dynamic && rows != static_cast<uint32_t>(T::RowsAtCompileTime)) ||
          (T::ColsAtCompileTime != Eigen::Dynamic && cols != static_cast<uint32_t>(T::ColsAtCompileTime)))
        fail("a matrix of " + std::to_string(rows) + "x" + std::to_string(cols) + " where its type has another size");
      const uint64_t bytes = uint64_t{rows} * cols * sizeof(typename T::Scalar);
      need(bytes, "a matrix");
      v.resize(rows, cols);
      raw(v.data(), static_cast<size_t>(bytes), "a matrix");
    } else if constexpr (std::is_same_v<T, Eigen::Quaterniond>) {
      raw(v.coeffs().data(), 4 * sizeof(double), "a quaternion");
    } else if constexpr (LoadsItself<T>) {
      v.load(*this);
    } else {
      load(*this, v);
    }
    return *this;
  }
  template <class A, class B>
  ArchiveReader& operator()(std::pair<A, B>& p) {
    return (*this)(p.first)(p.second);
  }
  template <class T>
  ArchiveReader& operator()(std::optional<T>& o) {
    bool has = false;
    (*this)(has);
    if (has) {
      T v{};
      (*this)(v);
      o = std::move(v);
    } else {
      o.reset();
    }
    return *this;
  }
  template <class T, class A>
  ArchiveReader& operator()(std::vector<T, A>& v) {
    return sequence(v);
  }
  template <class T, class A>
  ArchiveReader& operator()(std::deque<T, A>& v) {
    return sequence(v);
  }
  template <class... T>
  ArchiveReader& operator()(std::variant<T...>& v) {
    const auto index = get<uint32_t>();
    if (index >= sizeof...(T))
      fail("a variant of alternative " + std::to_string(index) + " of " + std::to_string(sizeof...(T)));
    load_alternative<0, T...>(index, v);
    return *this;
  }
  template <class K, class V, class C, class A>
  ArchiveReader& operator()(std::map<K, V, C, A>& m) {
    const uint64_t n = count(1, "a map");
    m.clear();
    for (uint64_t i = 0; i < n; ++i) {
      K k{};
      (*this)(k);
      V v{};
      (*this)(v);
      if (!m.emplace(std::move(k), std::move(v)).second) fail("a map with a duplicate key");
    }
    return *this;
  }

  template <class T>
  T get() {
    T v{};
    (*this)(v);
    return v;
  }

  /// Throws ArchiveError (naming the archive and the offset) with `what` was wrong.
  [[noreturn]] void fail(const std::string& what) const {
    throw ArchiveError(name_ + ": at byte " + std::to_string(at_) + ": " + what);
  }
  /// A count of elements of at least `min_bytes` each that the rest of the archive could hold.
  uint64_t count(size_t min_bytes, const char* what) {
    uint64_t n = 0;
    raw(&n, sizeof n, what);
    if (n > (size_ - at_) / (min_bytes == 0 ? 1 : min_bytes))
      fail(std::string(what) + " of " + std::to_string(n) + " elements, more than the " + std::to_string(size_ - at_) +
           " bytes left");
    return n;
  }
  size_t offset() const { return at_; }
  size_t remaining() const { return size_ - at_; }
  const std::string& name() const { return name_; }
  /// Throws unless every byte was read.
  void expect_end() const {
    if (at_ != size_) fail(std::to_string(size_ - at_) + " bytes left after the end of the state");
  }

 private:
  template <size_t I, class... T>
  void load_alternative(uint32_t index, std::variant<T...>& v) {
    if constexpr (I < sizeof...(T)) {
      if (index == I) {
        std::variant_alternative_t<I, std::variant<T...>> x{};
        (*this)(x);
        v = std::move(x);
      } else {
        load_alternative<I + 1, T...>(index, v);
      }
    }
  }
  void need(uint64_t n, const char* what) const {
    if (n > size_ - at_)
      fail(std::string("truncated: ") + what + " needs " + std::to_string(n) + " bytes, " +
           std::to_string(size_ - at_) + " left");
  }
  template <class S>
  ArchiveReader& sequence(S& s) {
    const uint64_t n = count(1, "a sequence");
    s.clear();
    for (uint64_t i = 0; i < n; ++i) {
      typename S::value_type x{};
      (*this)(x);
      s.push_back(std::move(x));
    }
    return *this;
  }

  const unsigned char* p_;
  size_t size_;
  size_t at_ = 0;
  std::string name_;
};

}  // namespace sextant::archive
