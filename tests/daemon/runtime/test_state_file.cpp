// The state file (daemon/runtime/state_file.hpp): sections round-trip through the file; every kind of damage (a
// flipped byte anywhere, truncation, another magic, version or config fingerprint) is refused with the file named;
// the atomic write leaves no temporary file; CRC-32 is zlib's.
#include "daemon/runtime/state_file.hpp"

#include <doctest/doctest.h>

#include <csignal>
#include <filesystem>
#include <sys/resource.h>
#include <string>
#include <unistd.h>

using namespace sextant;
using namespace sextant::runtime;

namespace {

std::string error_of(const std::string& bytes, uint64_t fingerprint) {
  try {
    decode_state(bytes, fingerprint, "/some/dir/sextantd.state");
  } catch (const StateFileError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("state file: CRC-32 is zlib's (IEEE 802.3)") {
  CHECK(crc32("123456789", 9) == 0xCBF43926u);  // the standard check value
  CHECK(crc32("", 0) == 0u);
}

TEST_CASE("state file: sections round-trip, every flipped byte and every truncation is refused, naming the file") {
  const std::vector<StateSection> sections{{"dead_reckoning", std::string("\x01\x02\x03", 3)},
                                           {"graph", std::string(300, 'g')}};
  const std::string bytes = encode_state(42, sections);
  const auto back = decode_state(bytes, 42, "f");
  REQUIRE(back.size() == 2);
  CHECK(back[0].name == "dead_reckoning");
  CHECK(back[0].bytes == sections[0].bytes);
  CHECK(back[1].bytes == sections[1].bytes);

  for (size_t i = 0; i < bytes.size(); ++i) {
    std::string bad = bytes;
    bad[i] = static_cast<char>(bad[i] ^ 0x10);
    const std::string e = error_of(bad, 42);
    CHECK_MESSAGE(e.rfind("/some/dir/sextantd.state: ", 0) == 0, "byte " << i << ": '" << e << "'");
  }
  for (size_t n = 0; n < bytes.size(); ++n) CHECK_FALSE(error_of(bytes.substr(0, n), 42).empty());
  CHECK(error_of(bytes + "x", 42).find("truncated or extended") != std::string::npos);
  CHECK(error_of(bytes, 43).find("another engine configuration") != std::string::npos);
  CHECK(error_of("hello", 42).find("too short") != std::string::npos);
  std::string other_version = bytes;
  other_version[16] = 1;  // the version before the graph stage's state became the SLAM layer's
  CHECK(error_of(other_version, 42)
            .find("state format version 1, this sextantd reads version " + std::to_string(kStateFormatVersion)) !=
        std::string::npos);
}

TEST_CASE("state file: written atomically, replacing the previous one, no temporary left") {
  const auto dir = std::filesystem::temp_directory_path() / ("sextant_state_file_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / kStateFileName).string();
  write_file_atomically(path, encode_state(1, {{"a", "first"}}));
  write_file_atomically(path, encode_state(1, {{"a", "second"}}));
  CHECK(decode_state(read_whole_file(path), 1, path)[0].bytes == "second");
  CHECK_FALSE(std::filesystem::exists(path + ".tmp"));
  CHECK_THROWS_AS(write_file_atomically((dir / "missing" / "x").string(), "y"), StateFileError);
  CHECK_THROWS_AS(read_whole_file((dir / "missing").string()), StateFileError);
  std::filesystem::remove_all(dir);
}

TEST_CASE("state file: a write that fails half way (a full disk) leaves the previous file whole and no temporary") {
  const auto dir = std::filesystem::temp_directory_path() / ("sextant_state_full_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / kStateFileName).string();
  write_file_atomically(path, encode_state(1, {{"a", "first"}}));
  // A file size limit makes write() fail with EFBIG part way, as ENOSPC does on a full disk.
  struct rlimit old {};
  REQUIRE(::getrlimit(RLIMIT_FSIZE, &old) == 0);
  const auto old_handler = std::signal(SIGXFSZ, SIG_IGN);
  struct rlimit small = old;
  small.rlim_cur = 4096;
  REQUIRE(::setrlimit(RLIMIT_FSIZE, &small) == 0);
  std::string error;
  try {
    write_file_atomically(path, encode_state(1, {{"a", std::string(100000, 'x')}}));
  } catch (const StateFileError& e) {
    error = e.what();
  }
  REQUIRE(::setrlimit(RLIMIT_FSIZE, &old) == 0);
  std::signal(SIGXFSZ, old_handler);
  CHECK(error.find("write failed") != std::string::npos);
  CHECK_FALSE(std::filesystem::exists(path + ".tmp"));
  CHECK(decode_state(read_whole_file(path), 1, path)[0].bytes == "first");
  std::filesystem::remove_all(dir);
}
