// The body of libsextant_rosbag.so (rosbag_plugin.hpp): convert_rosbag behind a C-linkage entry point.
#include "cli/rosbag_plugin/rosbag_plugin.hpp"

#include <exception>
#include <type_traits>

extern "C" __attribute__((visibility("default"))) void sextant_convert_rosbag(
    const std::string& bag, const std::string& out_lcm, const sextant::tools::RosbagConversionOptions& options,
    sextant::tools::RosbagConversion& result, std::string& error) {
  try {
    result = sextant::tools::convert_rosbag(bag, out_lcm, options);
  } catch (const std::exception& e) {
    error = e.what();
  }
}

// The entry point's type is the one the loader expects.
static_assert(std::is_same_v<decltype(sextant_convert_rosbag), sextant::cli::ConvertRosbagEntry>);
