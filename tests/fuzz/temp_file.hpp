#pragma once
// For harnesses of readers that take a path: the input written to a file of this process's own.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>

namespace sextant::fuzz {

/// A folder of this process under the temporary directory (created once).
inline std::string temp_dir() {
  static const std::string dir = [] {
    const auto d = std::filesystem::temp_directory_path() / ("sextant_fuzz_" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    return d.string();
  }();
  return dir;
}

/// Writes `size` bytes to `name` in temp_dir(); returns the path.
inline std::string write_temp(const std::string& name, const uint8_t* data, size_t size) {
  const std::string path = temp_dir() + "/" + name;
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) std::abort();
  if (size > 0 && std::fwrite(data, 1, size, f) != size) std::abort();
  std::fclose(f);
  return path;
}

}  // namespace sextant::fuzz
