# sextant's version string, stamped at build time (not configure time) into a one-function library,
# sextant_version (daemon/runtime/version.hpp): `git describe` of the checkout when it is one, else the project
# version.  The file is rewritten only when the string changes, so an unchanged checkout relinks nothing.
set(SEXTANT_VERSION_CPP ${CMAKE_BINARY_DIR}/generated/sextant_version.cpp)
add_custom_target(sextant_version_stamp
  COMMAND ${CMAKE_COMMAND} -DSOURCE_DIR=${CMAKE_SOURCE_DIR} -DOUT=${SEXTANT_VERSION_CPP}
          -DPROJECT_VERSION=${PROJECT_VERSION} -P ${CMAKE_SOURCE_DIR}/cmake/write_version.cmake
  BYPRODUCTS ${SEXTANT_VERSION_CPP}
  COMMENT "" VERBATIM)
add_library(sextant_version STATIC ${SEXTANT_VERSION_CPP})
add_dependencies(sextant_version sextant_version_stamp)
target_include_directories(sextant_version PUBLIC $<BUILD_INTERFACE:${CMAKE_SOURCE_DIR}>
                           $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}/sextant>)
