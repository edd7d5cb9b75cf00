# Install rules and the CMake package: find_package(voxfx) gives voxfx::voxfx.
#   <prefix>/include/voxfx/*.hpp, <libdir>/libvoxfx.{a,so}, <libdir>/voxfx/voxfx_*.so (modules),
#   <bindir>/voxfx, <libdir>/cmake/voxfx/voxfx{Config,ConfigVersion,Targets}.cmake
include(CMakePackageConfigHelpers)

set(VOXFX_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/voxfx)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/voxfx DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
        FILES_MATCHING PATTERN "*.hpp")
install(TARGETS voxfx EXPORT voxfxTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
# Found by the loader in ../lib/voxfx from bin/voxfx and in <libdir>/voxfx (configured path).
install(TARGETS ${VOXFX_MODULES} LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}/voxfx)
if(VOXFX_BUILD_CLI)
  install(TARGETS voxfx_cli RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endif()
install(EXPORT voxfxTargets NAMESPACE voxfx:: DESTINATION ${VOXFX_CMAKE_DIR})

# A static libvoxfx.a carries its private link dependencies (TBB, libpng, threads) to the
# consumer's link line, so the package must find them; a shared one does not.
get_target_property(VOXFX_LIBRARY_TYPE voxfx TYPE)
if(VOXFX_LIBRARY_TYPE STREQUAL "STATIC_LIBRARY")
  set(VOXFX_STATIC ON)
else()
  set(VOXFX_STATIC OFF)
endif()
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/voxfxConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/voxfxConfig.cmake INSTALL_DESTINATION ${VOXFX_CMAKE_DIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/voxfxConfigVersion.cmake VERSION ${PROJECT_VERSION}
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/voxfxConfig.cmake ${PROJECT_BINARY_DIR}/voxfxConfigVersion.cmake
        DESTINATION ${VOXFX_CMAKE_DIR})
