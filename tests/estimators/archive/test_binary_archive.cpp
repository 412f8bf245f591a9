// The binary archive (estimators/archive/binary_archive.hpp) that stages save their state with: values round-trip
// exactly, and counts, sizes and flags that do not fit the bytes left are refused before anything is allocated.
#include "estimators/archive/binary_archive.hpp"

#include <doctest/doctest.h>

#include <Eigen/Core>

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <variant>
#include <vector>

using namespace sextant;

TEST_CASE("archive: values round-trip exactly, counts and sizes beyond the bytes left are refused before allocating") {
  archive::ArchiveWriter w;
  const Eigen::Matrix3d m = Eigen::Matrix3d::Random();
  const Eigen::VectorXd v = Eigen::VectorXd::Random(5);
  std::map<int64_t, std::string> map{{-1, "a"}, {7, "bc"}};
  std::optional<double> some = 0.1, none;
  std::variant<int, std::string> var = std::string("x");
  w(int64_t{-5})(true)(0.1)(m)(v)(map)(some)(none)(var)(std::vector<double>{1.5, -2.5});
  const std::string b = w.take();
  archive::ArchiveReader r(b.data(), b.size(), "t");
  CHECK(r.get<int64_t>() == -5);
  CHECK(r.get<bool>());
  CHECK(r.get<double>() == 0.1);
  CHECK(r.get<Eigen::Matrix3d>() == m);
  CHECK(r.get<Eigen::VectorXd>() == v);
  CHECK(r.get<std::map<int64_t, std::string>>() == map);
  CHECK(r.get<std::optional<double>>() == some);
  CHECK_FALSE(r.get<std::optional<double>>().has_value());
  CHECK(std::get<std::string>(r.get<std::variant<int, std::string>>()) == "x");
  CHECK(r.get<std::vector<double>>() == std::vector<double>{1.5, -2.5});
  CHECK_NOTHROW(r.expect_end());

  // A count of 2^62 elements in a 12-byte archive, a matrix of the wrong fixed size, a bool of 2.
  archive::ArchiveWriter huge;
  huge(uint64_t{1} << 62)(uint32_t{0});
  archive::ArchiveReader hr(huge.data().data(), huge.data().size(), "huge");
  CHECK_THROWS_WITH_AS(hr.get<std::vector<double>>(), doctest::Contains("huge: at byte 8: a sequence of"),
                       archive::ArchiveError);
  archive::ArchiveWriter wrong;
  wrong(Eigen::Matrix2d::Identity().eval());
  archive::ArchiveReader wr(wrong.data().data(), wrong.data().size(), "wrong");
  CHECK_THROWS_AS(wr.get<Eigen::Matrix3d>(), archive::ArchiveError);
  const char two = 2;
  archive::ArchiveReader br(&two, 1, "flag");
  CHECK_THROWS_AS(br.get<bool>(), archive::ArchiveError);
}
