# `cmake --install`: the tools, libcwloc.so with its API headers, and the CMake package that
# lets another project write find_package(cwloc) and link cwloc::localizer (docs/api.md).
include(CMakePackageConfigHelpers)

install(TARGETS cwloc_api EXPORT cwlocTargets
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
# The result types' headers (results/) next to the API's, as the build tree has them.
list(TRANSFORM CWLOC_RESULT_HEADERS REPLACE "^.*/" "${PROJECT_BINARY_DIR}/generated/cwloc/"
  OUTPUT_VARIABLE CWLOC_INSTALLED_RESULT_HEADERS)
install(FILES api/include/cwloc/cwloc.hpp api/include/cwloc/cwloc.h
  ${PROJECT_BINARY_DIR}/generated/cwloc/options.inc ${CWLOC_INSTALLED_RESULT_HEADERS}
  DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/cwloc)

# cwloc-localize loads FFmpeg's module from here with its first --video (photo/video/).
if(TARGET cwloc_video_ffmpeg)
  install(TARGETS cwloc_video_ffmpeg LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
endif()
foreach(tool cwloc_localize_exe cwloc_index_exe cwloc_synth_exe cwloc_eval_exe)
  if(TARGET ${tool})
    install(TARGETS ${tool} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  endif()
endforeach()
if(CWLOC_BUILD_TOOLS)
  install(PROGRAMS ${CMAKE_RUNTIME_OUTPUT_DIRECTORY}/cwloc-plot DESTINATION ${CMAKE_INSTALL_BINDIR})
endif()

set(CWLOC_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/cwloc)
install(EXPORT cwlocTargets NAMESPACE cwloc:: DESTINATION ${CWLOC_CMAKE_DIR})
configure_package_config_file(cmake/cwlocConfig.cmake.in
  ${PROJECT_BINARY_DIR}/cwlocConfig.cmake INSTALL_DESTINATION ${CWLOC_CMAKE_DIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/cwlocConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/cwlocConfig.cmake ${PROJECT_BINARY_DIR}/cwlocConfigVersion.cmake
  DESTINATION ${CWLOC_CMAKE_DIR})
