# `cmake --install build --prefix P`: the libcalib headers (include/libcalib/...),
# its static libraries, the `rtscalib` binary and a CMake package, so that a
# program elsewhere writes
#   find_package(rtscalib REQUIRED)
#   target_link_libraries(app PRIVATE rtscalib::rtscalib)
# (docs/library.md). render/ and app/ stay out of the library: VTK is not a
# dependency of users.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

# Every rtscalib_add_layer call registers its target (libcalib/CMakeLists.txt).
get_property(rtscalib_installed_layers GLOBAL PROPERTY RTSCALIB_INSTALLED_LAYERS)
foreach(layer IN LISTS rtscalib_installed_layers)
  string(REPLACE "rtscalib_" "" short ${layer})
  set_target_properties(${layer} PROPERTIES EXPORT_NAME ${short})  # rtscalib::geometry, ...
endforeach()

# rtscalib::rtscalib: every layer; what a user links.
add_library(rtscalib_library INTERFACE)
target_link_libraries(rtscalib_library INTERFACE ${rtscalib_installed_layers})
set_target_properties(rtscalib_library PROPERTIES EXPORT_NAME rtscalib)
add_library(rtscalib::rtscalib ALIAS rtscalib_library)

set(rtscalib_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/rtscalib)
install(TARGETS ${rtscalib_installed_layers} rtscalib_library
        EXPORT rtscalibTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/libcalib/
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/libcalib
        FILES_MATCHING PATTERN "*.h")
install(EXPORT rtscalibTargets
        NAMESPACE rtscalib::
        FILE rtscalibTargets.cmake
        DESTINATION ${rtscalib_cmake_dir})
configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/rtscalibConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/rtscalibConfig.cmake
                              INSTALL_DESTINATION ${rtscalib_cmake_dir})
# 0.x: a new minor version may change the API, so only the same minor matches.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/rtscalibConfigVersion.cmake
                                 VERSION ${PROJECT_VERSION}
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/rtscalibConfig.cmake
              ${PROJECT_BINARY_DIR}/rtscalibConfigVersion.cmake
              ${CMAKE_CURRENT_LIST_DIR}/eigen_blas.cmake
              ${CMAKE_CURRENT_LIST_DIR}/blas_threads.cc
        DESTINATION ${rtscalib_cmake_dir})

install(TARGETS rtscalib RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
