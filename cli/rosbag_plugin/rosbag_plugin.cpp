#include "cli/rosbag_plugin/rosbag_plugin.hpp"

#include <dlfcn.h>
#include <unistd.h>

#include <climits>
#include <stdexcept>

namespace sextant::cli {
namespace {

// <directory of the running executable>/SEXTANT_ROSBAG_MODULE_DIR/libsextant_rosbag.so.
std::string module_path() {
  char exe[PATH_MAX];
  const ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
  if (n <= 0) throw std::runtime_error("cannot find the running executable (/proc/self/exe) to load the rosbag module");
  const std::string path(exe, static_cast<size_t>(n));
  return path.substr(0, path.rfind('/') + 1) + SEXTANT_ROSBAG_MODULE_DIR "/libsextant_rosbag.so";
}

ConvertRosbagEntry* load_entry() {
  const std::string path = module_path();
  void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);  // kept open for the process's life
  if (!handle) throw std::runtime_error("cannot load the rosbag module: " + std::string(dlerror()));
  void* entry = dlsym(handle, kConvertRosbagSymbol);
  if (!entry) throw std::runtime_error(path + ": no entry point " + kConvertRosbagSymbol);
  return reinterpret_cast<ConvertRosbagEntry*>(entry);
}

}  // namespace

tools::RosbagConversion convert_rosbag_via_module(const std::string& bag, const std::string& out_lcm,
                                                  const tools::RosbagConversionOptions& options) {
  static ConvertRosbagEntry* const entry = load_entry();
  tools::RosbagConversion result;
  std::string error;
  entry(bag, out_lcm, options, result, error);
  if (!error.empty()) throw std::runtime_error(error);
  return result;
}

}  // namespace sextant::cli
