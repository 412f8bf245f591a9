#include "convert/rosbag/rosbag_converter.hpp"

#include "daemon/runtime/lcm_log.hpp"

namespace sextant::tools {

RosbagConversion convert_rosbag(const std::string& bag, const std::string& out_lcm,
                                const RosbagConversionOptions& options) {
  runtime::LogWriter out(out_lcm);
  const RosbagConversion result =
      read_rosbag(bag, options, [&](int64_t utime, const std::string& channel, const std::vector<uint8_t>& bytes) {
        out.write_raw(utime, channel, bytes.data(), bytes.size());
      });
  out.flush();
  return result;
}

}  // namespace sextant::tools
