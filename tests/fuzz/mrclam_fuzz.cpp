// Fuzz harness: the MRCLAM converter.  The input is split at NUL bytes into the five files of one robot (barcodes,
// landmark truth, robot truth, odometry, measurements).  Contract checked: a conversion or a std::runtime_error
// (a barcode of 1e11 used to be cast to int: undefined behaviour, silently landmark 6).
#include "convert/mrclam_converter.hpp"
#include "temp_file.hpp"

#include <cstdlib>
#include <stdexcept>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const char* const kFiles[] = {"Barcodes.dat", "Landmark_Groundtruth.dat", "Robot1_Groundtruth.dat",
                                       "Robot1_Odometry.dat", "Robot1_Measurement.dat"};
  size_t start = 0;
  for (int f = 0; f < 5; ++f) {
    size_t end = start;
    while (end < size && data[end] != 0) ++end;
    sextant::fuzz::write_temp(kFiles[f], data + start, end - start);
    start = end < size ? end + 1 : size;
  }
  const std::string dir = sextant::fuzz::temp_dir();
  try {
    (void)sextant::tools::convert_mrclam(dir, 1, dir + "/out.lcm", dir + "/gt.txt");
  } catch (const std::runtime_error&) {}
  return 0;
}
