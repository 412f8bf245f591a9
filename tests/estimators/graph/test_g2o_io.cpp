// The g2o reader (estimators/graph/g2o_io.hpp) on files from outside: what used to cast out of range or read on
// silently is an error naming FILE:LINE.
#include "estimators/graph/g2o_io.hpp"

#include <doctest/doctest.h>

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
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

TEST_CASE("g2o: every spelling strtod reads is strtod's value, however blanks, tabs, CR, comments space the line") {
  // Decimals (through from_chars) and what only strtod reads (a '+', hexadecimal, out of range) must agree with
  // strtod to the bit, however the line is spaced.
  const char* spellings[] = {"0.1", "-2.5e-3", "+1.25", "0x1.8p1", "1e-320", "3.14159265358979323846", "7"};
  for (const char* x : spellings) {
    const auto path = temp("numbers.g2o");
    std::ofstream(path) << "VERTEX_SE2 0 0 0 0\t# a comment\r\nVERTEX_SE2  1 \t" << x << "  0.5   " << x
                        << " \r\nEDGE_SE2 0 1 " << x << " 0 0 1 0 0 1 0 1\n";
    const auto g = graph::read_g2o(path);
    const double expect = std::strtod(x, nullptr);
    REQUIRE(g.graph.variables().size() == 2);
    CHECK(g.graph.variables()[1].pose2.translation().x() == expect);
    CHECK(g.graph.variables()[1].pose2.translation().y() == 0.5);
    CHECK(g.graph.factors().size() == 1);
    std::remove(path.c_str());
  }
  const auto path = temp("bad_number.g2o");
  std::ofstream(path) << "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 0.5x 0 0\n";
  CHECK_THROWS_WITH(graph::read_g2o(path), doctest::Contains((path + ":2: VERTEX_SE2: not a number: '0.5x'").c_str()));
  std::ofstream(path) << "VERTEX_SE2 0 0 0 0 9\n";
  CHECK_THROWS_WITH(graph::read_g2o(path), doctest::Contains((path + ":1: VERTEX_SE2: 1 unexpected extra").c_str()));
  std::remove(path.c_str());
}
