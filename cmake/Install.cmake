# Installation and the CMake package springlab (see CMakeLists.txt).
include(CMakePackageConfigHelpers)

install(TARGETS springlab_core springlab_plugin ${SPRINGLAB_WINGS} springlab_cholmod EXPORT springlabTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/springlab)
install(TARGETS springlab RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
foreach(layer models integrators experiments)
  # CONFIGURE_DEPENDS: a header added later is installed without a fresh configure.
  file(GLOB_RECURSE headers CONFIGURE_DEPENDS RELATIVE ${PROJECT_SOURCE_DIR}
       ${PROJECT_SOURCE_DIR}/${layer}/*.h)
  foreach(header IN LISTS headers)
    get_filename_component(dir ${header} DIRECTORY)
    install(FILES ${PROJECT_SOURCE_DIR}/${header} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/springlab/${dir})
  endforeach()
endforeach()

set(SPRINGLAB_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/springlab)
install(EXPORT springlabTargets NAMESPACE springlab:: DESTINATION ${SPRINGLAB_CMAKE_DIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/springlabConfig.cmake.in
  ${PROJECT_BINARY_DIR}/springlabConfig.cmake INSTALL_DESTINATION ${SPRINGLAB_CMAKE_DIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/springlabConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/springlabConfig.cmake
              ${PROJECT_BINARY_DIR}/springlabConfigVersion.cmake
              ${PROJECT_SOURCE_DIR}/cmake/SpringlabPlugin.cmake
        DESTINATION ${SPRINGLAB_CMAKE_DIR})
