// Fuzz harness: the g2o reader.  Contract checked: a graph or a std::runtime_error naming FILE:LINE, nothing else.
#include "estimators/graph/g2o_io.hpp"
#include "temp_file.hpp"

#include <cstdlib>
#include <stdexcept>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = sextant::fuzz::write_temp("in.g2o", data, size);
  try {
    (void)sextant::graph::read_g2o(path);
  } catch (const std::runtime_error& e) {
    if (std::string(e.what()).rfind(path, 0) != 0) std::abort();  // every error names the file
  } catch (const std::invalid_argument&) {
    // The factor graph's own checks (a duplicate id, a bad kernel) surface as invalid_argument.
  }
  return 0;
}
