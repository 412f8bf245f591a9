# ROS 1's bag reader as Debian ships it (librosbag-storage-dev, with the message headers of libsensor-msgs-dev,
# libnav-msgs-dev, libgeometry-msgs-dev).  Debian's ROS 1 rosbag_storage headers include pluginlib and class_loader,
# which Debian now ships in their ROS 2 versions (pluginlib-dev, libclass-loader-dev: headers one directory deeper,
# needing rcpputils, rcutils and ament_index_cpp); those satisfy the bag reader's (unused) encryption plugin loader.
# Target: sextant_rosbag_deps (INTERFACE), for `sextant convert rosbag` only.
set(_ros_libs rosbag_storage roscpp_serialization rostime cpp_common console_bridge class_loader ament_index_cpp
    rcpputils rcutils)
add_library(sextant_rosbag_deps INTERFACE)
foreach(l ${_ros_libs})
  find_library(SEXTANT_ROS_${l} ${l} REQUIRED)
  target_link_libraries(sextant_rosbag_deps INTERFACE ${SEXTANT_ROS_${l}})
endforeach()
find_path(SEXTANT_ROSBAG_INCLUDE rosbag/bag.h REQUIRED)
foreach(h pluginlib/class_loader.hpp class_loader/multi_library_class_loader.hpp rcpputils/shared_library.hpp
          rcutils/types.h ament_index_cpp/get_package_prefix.hpp)
  get_filename_component(d ${h} DIRECTORY)
  find_path(SEXTANT_ROS_INCLUDE_${d} ${h} PATH_SUFFIXES ${d} REQUIRED)
  target_include_directories(sextant_rosbag_deps SYSTEM INTERFACE ${SEXTANT_ROS_INCLUDE_${d}})
endforeach()
