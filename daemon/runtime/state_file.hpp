#pragma once
// The daemon's state file (README, "State directory"): the saved state of every engine stage, written atomically
// and read back at start.  Layout (little-endian):
//   magic "SEXTANT-STATE\n\0\0" (16 bytes), format version (u32), config fingerprint (u64: of the parsed engine
//   config's values, daemon_config.hpp), payload size (u64), CRC-32 of the payload (u32), payload.
//   payload: sections, each a name (the stage's) and its bytes (binary_archive.hpp), in stage order.
// Writing: a temporary file beside the target, fsync, rename over the target, fsync of the directory: a crash at any
// moment leaves the previous complete file or the new one, never a torn one.
// Reading checks everything before any stage sees a byte: a file that is short, has another magic, another version,
// a wrong checksum or another config's fingerprint throws StateFileError naming the file and what is wrong.
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace sextant::runtime {

class StateFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct StateSection {
  std::string name;   // the stage's name
  std::string bytes;  // what Stage::save wrote
};

/// Version 3: the graph pose stage keeps no per-body publication time (the publisher's rule is the only one).
/// Version 2: the graph stage's section is the SLAM layer's state (estimators/slam/slam_graph.hpp) between the stage's
/// counters and its per-body TRAJECTORY feeds.  Files of another version are refused.
/// Version 4: every estimator also keeps the steps it refused as unhealthy (estimators/filter/estimate_health.hpp)
/// and its association budget counters.
/// Version 9: a lifelong graph's thinned-keyframe records carry their place (keyframe_track.hpp).
inline constexpr uint32_t kStateFormatVersion = 9;
/// The state file inside a state directory.
inline constexpr const char* kStateFileName = "sextantd.state";

/// CRC-32 (IEEE 802.3, reflected, as zlib's crc32) of `n` bytes.
uint32_t crc32(const void* data, size_t n);

/// The file's bytes for these sections.
std::string encode_state(uint64_t fingerprint, const std::vector<StateSection>& sections);
/// The sections of a file's bytes; `path` names it in errors.  Throws StateFileError.
std::vector<StateSection> decode_state(const std::string& bytes, uint64_t fingerprint, const std::string& path);

/// Writes `bytes` to `path` atomically (temporary file, fsync, rename, directory fsync).  Throws StateFileError.
void write_file_atomically(const std::string& path, const std::string& bytes);
/// The bytes of `path`.  Throws StateFileError.
std::string read_whole_file(const std::string& path);

}  // namespace sextant::runtime
