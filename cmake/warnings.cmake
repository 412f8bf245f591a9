# Warnings as errors on sextant's own code (not on generated lcm-gen code).
function(sextant_warnings target)
  # -Wmaybe-uninitialized is off: GCC 12 raises it inside lcm-gen's inlined decode functions (false positives).
  # Errors with GCC, the project's compiler; clang (`make fuzz` only) warns.
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wno-error=deprecated-declarations
                         "$<$<CXX_COMPILER_ID:GNU>:-Werror;-Wno-maybe-uninitialized>")
endfunction()

# A static library from the .cpp files matched by the given globs (relative to the current folder).
# Usage: sextant_library(name GLOBS lie/*.cpp graph/*.cpp)
function(sextant_library name)
  cmake_parse_arguments(ARG "" "" "GLOBS" ${ARGN})
  set(srcs)
  foreach(g ${ARG_GLOBS})
    file(GLOB found CONFIGURE_DEPENDS "${CMAKE_CURRENT_SOURCE_DIR}/${g}")
    list(APPEND srcs ${found})
  endforeach()
  if(NOT srcs)  # a folder whose first source has not landed yet still configures
    set(srcs ${CMAKE_CURRENT_BINARY_DIR}/${name}_empty.cpp)
    file(WRITE ${srcs} "")
  endif()
  add_library(${name} STATIC ${srcs})
  # Headers are included by their path from the project root ("estimators/graph/optimizer.hpp"), in the tree and
  # installed (under include/sextant/, cmake/install.cmake).
  target_include_directories(${name} PUBLIC $<BUILD_INTERFACE:${CMAKE_SOURCE_DIR}>
                             $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}/sextant>)
  sextant_warnings(${name})
endfunction()
