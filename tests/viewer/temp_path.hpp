#pragma once
// A file name of this test process's own under the temporary directory.
#include <unistd.h>

#include <filesystem>
#include <string>

namespace sextant::viewer::test {

inline std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("sextant_viewer_" + std::to_string(::getpid()) + "_" + name))
      .string();
}

}  // namespace sextant::viewer::test
