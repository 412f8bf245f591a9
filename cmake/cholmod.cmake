# CHOLMOD from Debian's SuiteSparse (5.x ships no CMake config): an imported target SuiteSparse::CHOLMOD.
# Also installed with sextant's CMake package (cmake/install.cmake), so a consumer finds CHOLMOD the same way.
if(TARGET SuiteSparse::CHOLMOD)
  return()
endif()
find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse REQUIRED)
find_library(CHOLMOD_LIBRARY cholmod REQUIRED)
find_library(SUITESPARSE_CONFIG_LIBRARY suitesparseconfig REQUIRED)
add_library(SuiteSparse::CHOLMOD UNKNOWN IMPORTED)
set_target_properties(SuiteSparse::CHOLMOD PROPERTIES
  IMPORTED_LOCATION "${CHOLMOD_LIBRARY}"
  INTERFACE_INCLUDE_DIRECTORIES "${CHOLMOD_INCLUDE_DIR}"
  INTERFACE_LINK_LIBRARIES "${SUITESPARSE_CONFIG_LIBRARY}")
