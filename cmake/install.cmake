# `cmake --install BUILD [--prefix P]`: what an adopter needs, laid out as Debian packages lay theirs out.
#   bin/                          sextantd, sextant
#   lib/libsextant_*.a            the libraries (position-independent static archives)
#   lib/sextant/libsextant_rosbag.so  the module `sextant convert rosbag` loads (ROS's bag library)
#   include/sextant/              their headers, included by path from the project root ("estimators/graph/optimizer.hpp"),
#                                 and lcm-gen's C++ message headers ("sextant/odometry_t.hpp")
#   lib/cmake/sextant/            the CMake package: find_package(sextant) -> sextant::estimators, sextant::assoc, ...
#   share/sextant/lcmtypes/       the .lcm message definitions (lcm-gen them for another language)
#   share/sextant/config/         default.yaml and the bundled configs
#   share/java/sextant_types.jar  the Java message classes for lcm-spy
#   lib/systemd/system/           sextantd.service, its paths set to this prefix
#   lib/python3.X/dist-packages/  the sextant Python module (python/CMakeLists.txt)
include(CMakePackageConfigHelpers)
set(SEXTANT_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/sextant)

# Exported as sextant::<name> without the "sextant_" of the build-tree name.
set(sextant_exported assoc estimators engine config runtime replay eval sim convert report cli lcmtypes version)
foreach(n ${sextant_exported})
  set_target_properties(sextant_${n} PROPERTIES EXPORT_NAME ${n})
  list(APPEND sextant_export_targets sextant_${n})
endforeach()
install(TARGETS ${sextant_export_targets} EXPORT sextantTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/sextant)
install(TARGETS sextantd sextant RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(TARGETS sextant_rosbag_module LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}/sextant)  # for `sextant convert rosbag`
install(EXPORT sextantTargets NAMESPACE sextant:: DESTINATION ${SEXTANT_CMAKE_DIR})

configure_package_config_file(${CMAKE_SOURCE_DIR}/cmake/sextantConfig.cmake.in
  ${CMAKE_BINARY_DIR}/generated/sextantConfig.cmake INSTALL_DESTINATION ${SEXTANT_CMAKE_DIR})
write_basic_package_version_file(${CMAKE_BINARY_DIR}/generated/sextantConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_BINARY_DIR}/generated/sextantConfig.cmake ${CMAKE_BINARY_DIR}/generated/sextantConfigVersion.cmake
              ${CMAKE_SOURCE_DIR}/cmake/cholmod.cmake
        DESTINATION ${SEXTANT_CMAKE_DIR})

# Headers of every installed library (the CLI's command plumbing stays private, and so do the incremental smoother's steps:
# estimators/graph/incremental_smoother.hpp is their public face and includes none of them).
foreach(dir estimators assoc daemon/engine daemon/config daemon/runtime replay eval sim convert report cli)
  install(DIRECTORY ${CMAKE_SOURCE_DIR}/${dir}/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/sextant/${dir}
          FILES_MATCHING PATTERN "*.hpp"
          REGEX "/cli/(command|handle_until_stopped|log_damage_report)\\.hpp$" EXCLUDE REGEX "/estimators/graph/smoother$" EXCLUDE)
endforeach()
install(DIRECTORY ${CMAKE_BINARY_DIR}/lcmtypes/cpp/sextant/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/sextant/sextant
        FILES_MATCHING PATTERN "*.hpp")

install(DIRECTORY ${CMAKE_SOURCE_DIR}/lcmtypes/sextant/ DESTINATION ${CMAKE_INSTALL_DATADIR}/sextant/lcmtypes/sextant
        FILES_MATCHING PATTERN "*.lcm")
install(DIRECTORY ${CMAKE_SOURCE_DIR}/config/ DESTINATION ${CMAKE_INSTALL_DATADIR}/sextant/config
        FILES_MATCHING PATTERN "*.yaml")
if(TARGET sextant_lcmtypes_java)
  install(FILES ${CMAKE_BINARY_DIR}/lcmtypes/sextant_types.jar DESTINATION ${CMAKE_INSTALL_DATADIR}/java)
endif()

# The unit in config/ names the default prefix (/usr/local); the installed copy names the prefix of the install
# (`cmake --install --prefix P` included, so this runs at install time).
install(CODE "
  file(READ \"${CMAKE_SOURCE_DIR}/config/sextantd.service\" unit)
  string(REPLACE \"/usr/local/\" \"\${CMAKE_INSTALL_PREFIX}/\" unit \"\${unit}\")
  set(dest \"\$ENV{DESTDIR}\${CMAKE_INSTALL_PREFIX}/lib/systemd/system/sextantd.service\")
  message(STATUS \"Installing: \${dest}\")
  file(WRITE \"\${dest}\" \"\${unit}\")
  list(APPEND CMAKE_INSTALL_MANIFEST_FILES \"\${dest}\")
")
