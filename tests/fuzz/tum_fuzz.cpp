// Fuzz harness: the TUM trajectory reader and the TUM -> LCM converter (a 9e12-second gap used to loop 10^14 times).
// Contract checked: poses or a std::runtime_error naming the file, and the conversion ends.
#include "eval/trajectory_io.hpp"
#include "convert/tum_converter.hpp"
#include "temp_file.hpp"

#include <cstdlib>
#include <stdexcept>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = sextant::fuzz::write_temp("gt.txt", data, size);
  try {
    (void)sextant::tools::read_tum(path);
    sextant::tools::TumConversionOptions o;
    o.frame_rate_hz = 30;
    (void)sextant::tools::convert_tum(path, sextant::fuzz::temp_dir() + "/out.lcm", o);
  } catch (const std::runtime_error& e) {
    if (std::string(e.what()).find(path) == std::string::npos) std::abort();
  }
  return 0;
}
