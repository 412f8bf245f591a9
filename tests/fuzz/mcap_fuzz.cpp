// Fuzz harness: the MCAP reader (magic, header, footer, summary, chunks with their zstd frames and CRCs, records in
// and out of chunks) and the MCAP -> LCM conversion behind it (each sextant channel's JSON re-encoded as LCM).
// Contract checked: a conversion or a std::runtime_error naming the file, in bounded memory (libFuzzer's
// -malloc_limit_mb catches an allocation the file's size does not justify).
#include "viewer/lcm_mcap.hpp"
#include "temp_file.hpp"

#include <cstdlib>
#include <stdexcept>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = sextant::fuzz::write_temp("in.mcap", data, size);
  try {
    (void)sextant::viewer::convert_mcap_to_lcm(path, sextant::fuzz::temp_dir() + "/out.lcm");
  } catch (const std::runtime_error& e) {
    if (std::string(e.what()).find(path) == std::string::npos) std::abort();
  }
  return 0;
}
