#pragma once
// For harnesses of readers that take a path: the input written to a file of this process's own.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <system_error>

namespace sextant::fuzz {

/// A folder of this process in memory (/dev/shm) when there is one, else under the temporary directory (created
/// once).  On a disk, truncating and writing the input file took 2.5 ms per run here, 200 times the harness's work.
inline std::string temp_dir() {
  // Removed when the process exits (libFuzzer and the replay driver both leave through exit()).
  struct Dir {
    std::string path;
    ~Dir() {
      std::error_code ec;
      std::filesystem::remove_all(path, ec);
    }
  };
  static const Dir dir{[] {
    const std::filesystem::path base = std::filesystem::is_directory("/dev/shm")
                                           ? std::filesystem::path("/dev/shm")
                                           : std::filesystem::temp_directory_path();
    const auto d = base / ("sextant_fuzz_" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    return d.string();
  }()};
  return dir.path;
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
