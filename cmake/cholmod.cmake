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

# The BLAS CHOLMOD gets (libblas.so.3, Debian's alternative: OpenBLAS as installed) is named first among a program's
# libraries.  The dynamic loader resolves a symbol by searching the loaded libraries in breadth-first order of their
# DT_NEEDED entries; OpenBLAS binds some 14,000 references to its own functions at start-up, and each lookup passes
# every library ahead of it.  Named first, the BLAS and the OpenBLAS it loads come 8 places earlier: about 1 ms less
# start-up for every sextant process (bench/results/small_problems.md).  Which BLAS is used does not change.
find_library(SEXTANT_BLAS_LIBRARY NAMES blas)
if(SEXTANT_BLAS_LIBRARY)
  set_property(TARGET SuiteSparse::CHOLMOD APPEND PROPERTY INTERFACE_LINK_OPTIONS
    "LINKER:--push-state,--no-as-needed" "${SEXTANT_BLAS_LIBRARY}" "LINKER:--pop-state")
endif()
