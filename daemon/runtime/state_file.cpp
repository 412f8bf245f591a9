#include "daemon/runtime/state_file.hpp"

#include "estimators/archive/binary_archive.hpp"

#include <array>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fcntl.h>
#include <unistd.h>

namespace sextant::runtime {
namespace {

constexpr char kMagic[16] = {'S', 'E', 'X', 'T', 'A', 'N', 'T', '-', 'S', 'T', 'A', 'T', 'E', '\n', 0, 0};
constexpr size_t kHeaderSize = 16 + 4 + 8 + 8 + 4;

std::array<uint32_t, 256> crc_table() {
  std::array<uint32_t, 256> t{};
  for (uint32_t i = 0; i < 256; ++i) {
    uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    t[i] = c;
  }
  return t;
}

std::string errno_text() { return std::strerror(errno); }

}  // namespace

uint32_t crc32(const void* data, size_t n) {
  static const std::array<uint32_t, 256> table = crc_table();
  const auto* p = static_cast<const unsigned char*>(data);
  uint32_t c = 0xFFFFFFFFu;
  for (size_t i = 0; i < n; ++i) c = table[(c ^ p[i]) & 0xFFu] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}

std::string encode_state(uint64_t fingerprint, const std::vector<StateSection>& sections) {
  archive::ArchiveWriter payload;
  payload(static_cast<uint64_t>(sections.size()));
  for (const auto& s : sections) payload(s.name)(s.bytes);
  archive::ArchiveWriter file;
  file.raw(kMagic, sizeof kMagic);
  file(kStateFormatVersion)(fingerprint)(static_cast<uint64_t>(payload.data().size()))(
      crc32(payload.data().data(), payload.data().size()));
  file.raw(payload.data().data(), payload.data().size());
  return file.take();
}

std::vector<StateSection> decode_state(const std::string& bytes, uint64_t fingerprint, const std::string& path) {
  const auto bad = [&](const std::string& why) { return StateFileError(path + ": " + why); };
  if (bytes.size() < kHeaderSize || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
    throw bad(bytes.size() < sizeof kMagic
                  ? "too short to be a sextantd state file (" + std::to_string(bytes.size()) + " bytes)"
                  : "not a sextantd state file (no SEXTANT-STATE header)");
  archive::ArchiveReader header(bytes.data() + sizeof kMagic, kHeaderSize - sizeof kMagic, path);
  const auto version = header.get<uint32_t>();
  const auto file_fingerprint = header.get<uint64_t>();
  const auto size = header.get<uint64_t>();
  const auto crc = header.get<uint32_t>();
  if (version != kStateFormatVersion)
    throw bad("state format version " + std::to_string(version) + ", this sextantd reads version " +
              std::to_string(kStateFormatVersion));
  if (size != bytes.size() - kHeaderSize)
    throw bad("truncated or extended: the header says " + std::to_string(size) + " bytes of state, the file has " +
              std::to_string(bytes.size() - kHeaderSize));
  if (crc32(bytes.data() + kHeaderSize, size) != crc) throw bad("checksum mismatch: the file is damaged");
  if (file_fingerprint != fingerprint)
    throw bad("written with another engine configuration (fingerprint " + std::to_string(file_fingerprint) +
              ", this config's is " + std::to_string(fingerprint) + ")");
  try {
    archive::ArchiveReader r(bytes.data() + kHeaderSize, size, path);
    std::vector<StateSection> sections(r.count(16, "the sections"));
    for (auto& s : sections) r(s.name)(s.bytes);
    r.expect_end();
    return sections;
  } catch (const archive::ArchiveError& e) {
    throw StateFileError(e.what());
  }
}

void write_file_atomically(const std::string& path, const std::string& bytes) {
  const std::string tmp = path + ".tmp";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw StateFileError(tmp + ": cannot create: " + errno_text());
  // Any failure removes the partial file: PATH keeps the last complete state, nothing else is left behind.
  const auto fail = [&](const std::string& what, bool open) {
    const std::string why = errno_text();
    if (open) ::close(fd);
    ::unlink(tmp.c_str());
    throw StateFileError(tmp + ": " + what + " failed: " + why);
  };
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) fail("write", true);
    done += static_cast<size_t>(n);
  }
  if (::fsync(fd) != 0) fail("fsync", true);
  if (::close(fd) != 0) fail("close", false);
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string why = errno_text();
    ::unlink(tmp.c_str());
    throw StateFileError(path + ": rename failed: " + why);
  }
  const std::string dir = std::filesystem::path(path).parent_path().string();
  const int dfd = ::open(dir.empty() ? "." : dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd >= 0) {
    ::fsync(dfd);
    ::close(dfd);
  }
}

std::string read_whole_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw StateFileError(path + ": cannot open: " + errno_text());
  std::ostringstream s;
  s << in.rdbuf();
  if (in.bad()) throw StateFileError(path + ": read failed");
  return s.str();
}

}  // namespace sextant::runtime
