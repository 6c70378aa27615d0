# SPDX-License-Identifier: MIT
# Install rules: the runtime library, its headers and the generated schema
# header; with the compiler, bspc, its manual page, the compiler library and
# its headers; a CMake package (find_package(bspf): bspf::runtime, bspf::bspc,
# bspf::compiler as a component, bspf_add_level) and a pkg-config file for the
# runtime (bspf.pc).
include(CMakePackageConfigHelpers)
set(BSPF_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/bspf
    CACHE STRING "Where the bspf CMake package is installed, under the prefix")

# Runtime: library, public headers, generated schema header.
install(TARGETS bspf_runtime bspf_schema EXPORT bspfRuntimeTargets)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/runtime/include/bspf
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} FILES_MATCHING PATTERN "*.h")
install(FILES ${PROJECT_BINARY_DIR}/schema/include/bspf/bspf_generated.h
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/bspf)
install(EXPORT bspfRuntimeTargets NAMESPACE bspf:: DESTINATION ${BSPF_INSTALL_CMAKEDIR})

# Compiler: bspc (bspf::bspc, for bspf_add_level) in an export set of its
# own, so using it needs no assimp; the library (bspf::compiler) in another.
if(BSPF_BUILD_COMPILER)
  install(TARGETS bspc EXPORT bspfBspcTargets)
  install(EXPORT bspfBspcTargets NAMESPACE bspf:: DESTINATION ${BSPF_INSTALL_CMAKEDIR})
  install(FILES ${PROJECT_SOURCE_DIR}/docs/bspc.1 DESTINATION ${CMAKE_INSTALL_MANDIR}/man1)
  install(TARGETS bspc_lib EXPORT bspfCompilerTargets)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/compiler/include/bspc
          DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} FILES_MATCHING PATTERN "*.h")
  install(EXPORT bspfCompilerTargets NAMESPACE bspf:: DESTINATION ${BSPF_INSTALL_CMAKEDIR})
endif()

configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/bspfConfig.cmake.in
  ${PROJECT_BINARY_DIR}/bspfConfig.cmake INSTALL_DESTINATION ${BSPF_INSTALL_CMAKEDIR})
# 0.x: a minor version may break the interface.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/bspfConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/bspfConfig.cmake ${PROJECT_BINARY_DIR}/bspfConfigVersion.cmake
              ${PROJECT_SOURCE_DIR}/cmake/bspfLevels.cmake
        DESTINATION ${BSPF_INSTALL_CMAKEDIR})

# pkg-config: the prefix found from the .pc file's own place, so the file is
# right for `cmake --install --prefix` at any prefix.
if(IS_ABSOLUTE "${CMAKE_INSTALL_LIBDIR}")
  set(BSPF_PC_LIBDIR "${CMAKE_INSTALL_LIBDIR}")
else()
  set(BSPF_PC_LIBDIR "\${prefix}/${CMAKE_INSTALL_LIBDIR}")
endif()
if(IS_ABSOLUTE "${CMAKE_INSTALL_INCLUDEDIR}")
  set(BSPF_PC_INCLUDEDIR "${CMAKE_INSTALL_INCLUDEDIR}")
else()
  set(BSPF_PC_INCLUDEDIR "\${prefix}/${CMAKE_INSTALL_INCLUDEDIR}")
endif()
file(RELATIVE_PATH BSPF_PC_UP /prefix/${CMAKE_INSTALL_LIBDIR}/pkgconfig /prefix)
get_target_property(BSPF_PC_LIBNAME bspf_runtime OUTPUT_NAME)
if(NOT BSPF_PC_LIBNAME)
  set(BSPF_PC_LIBNAME bspf_runtime)
endif()
configure_file(${PROJECT_SOURCE_DIR}/cmake/bspf.pc.in ${PROJECT_BINARY_DIR}/bspf.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/bspf.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
