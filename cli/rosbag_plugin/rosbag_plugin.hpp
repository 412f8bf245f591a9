#pragma once
// `sextant convert rosbag` reads bags with ROS's bag library, whose dependencies (roslib, rospack and through it
// libpython, boost, class_loader, console_bridge, ...) are about twenty shared libraries with some 15 000 symbol
// relocations.  Linked into `sextant`, the dynamic loader would bind them at every start of every subcommand (a
// `sextant optimize` of a small graph spent about a quarter of its time there).  So the converter is a module,
// libsextant_rosbag.so in SEXTANT_ROSBAG_MODULE_DIR (relative to the directory of the running `sextant`: the same
// layout in the build tree as installed), loaded when a bag is converted and never otherwise.
#include "convert/rosbag/rosbag_converter.hpp"

#include <string>

namespace sextant::cli {

/// The module's one entry point, looked up by this name (C linkage, no name mangling): convert_rosbag, its
/// exception (if any) returned as a message in `error` rather than thrown across the module's boundary.
using ConvertRosbagEntry = void(const std::string& bag, const std::string& out_lcm,
                                const tools::RosbagConversionOptions& options, tools::RosbagConversion& result,
                                std::string& error);
inline constexpr const char* kConvertRosbagSymbol = "sextant_convert_rosbag";

/// convert_rosbag through the module, loaded on first use; throws std::runtime_error naming the module's path when
/// it cannot be loaded, and the conversion's own error as std::runtime_error.
tools::RosbagConversion convert_rosbag_via_module(const std::string& bag, const std::string& out_lcm,
                                                  const tools::RosbagConversionOptions& options);

}  // namespace sextant::cli
