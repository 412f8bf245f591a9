// The g2o reader (estimators/graph/g2o_io.hpp) on files from outside: what used to cast out of range or read on
// silently is an error naming FILE:LINE.
#include "estimators/graph/g2o_io.hpp"

#include <doctest/doctest.h>

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

using namespace sextant;

namespace {
std::string temp(const std::string& n) {
  return (std::filesystem::temp_directory_path() / ("sextant_g2o_io_" + std::to_string(::getpid()) + "_" + n)).string();
}
}  // namespace

TEST_CASE("g2o: an id outside int64's range is an error naming FILE:LINE, not a cast") {
  const auto path = temp("ids.g2o");
  std::ofstream(path) << "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1e30 0 0 0\n";
  CHECK_THROWS_WITH(graph::read_g2o(path),
                    doctest::Contains((path + ":2: VERTEX_SE2: id out of range: '1e30'").c_str()));
  std::ofstream(path) << "VERTEX_SE2 nan 0 0 0\n";
  CHECK_THROWS_WITH(graph::read_g2o(path), doctest::Contains((path + ":1: VERTEX_SE2: id out of range").c_str()));
  std::remove(path.c_str());
}
