# Installation and the CMake package of Quadrix (`cmake --install build --prefix P`, then
# `find_package(Quadrix)` with CMAKE_PREFIX_PATH=P in another project). Included by the top-level
# CMakeLists.txt after every target exists. Installs:
#   lib/                 the four libraries (static) as the imported targets Quadrix::geometry,
#                        Quadrix::fitting, Quadrix::matching, Quadrix::estimation (link this one)
#   include/quadrix/     their public headers, included as "estimation/registration.h" etc.
#   bin/                 the `quadrix` command line and `quadrix-baselines` (found beside it by `bench`)
#   lib/cmake/Quadrix/   QuadrixConfig.cmake, QuadrixConfigVersion.cmake, QuadrixTargets.cmake
#   share/quadrix/       the learned fitter's weights (point QUADRIX_LEARNED_FITTER_DIR at them)
#   lib/python3/dist-packages/   the Python module (python/CMakeLists.txt)
include(CMakePackageConfigHelpers)

set(QUADRIX_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/Quadrix)
set(QUADRIX_PACKAGE_LIBRARIES quadrix_geometry quadrix_fitting quadrix_matching quadrix_estimation)

# Short exported names (Quadrix::estimation) and the same names inside this build, so code written
# against the package also builds with add_subdirectory(quadrix).
foreach(library ${QUADRIX_PACKAGE_LIBRARIES})
  string(REGEX REPLACE "^quadrix_" "" short ${library})
  set_target_properties(${library} PROPERTIES EXPORT_NAME ${short})
  add_library(Quadrix::${short} ALIAS ${library})
endforeach()
# quadrix_pcl is the INTERFACE target through which the libraries link PCL privately; a static
# library's private dependencies are still link dependencies of its consumers, so it is exported too.
set_target_properties(quadrix_pcl PROPERTIES EXPORT_NAME pcl)

install(TARGETS ${QUADRIX_PACKAGE_LIBRARIES} quadrix_pcl
        EXPORT QuadrixTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
foreach(folder geometry fitting matching estimation)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${folder}/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/quadrix/${folder}
          FILES_MATCHING PATTERN "*.h" PATTERN "training" EXCLUDE PATTERN "models" EXCLUDE)
endforeach()
install(DIRECTORY ${PROJECT_SOURCE_DIR}/fitting/models/learned_fitter DESTINATION ${CMAKE_INSTALL_DATADIR}/quadrix)
install(TARGETS quadrix quadrix-baselines RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})

install(EXPORT QuadrixTargets NAMESPACE Quadrix:: FILE QuadrixTargets.cmake DESTINATION ${QUADRIX_INSTALL_CMAKEDIR})
configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/QuadrixConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/cmake/QuadrixConfig.cmake
                              INSTALL_DESTINATION ${QUADRIX_INSTALL_CMAKEDIR})
# 0.x: only the same minor version is compatible.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/cmake/QuadrixConfigVersion.cmake
                                 VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/cmake/QuadrixConfig.cmake ${PROJECT_BINARY_DIR}/cmake/QuadrixConfigVersion.cmake
        DESTINATION ${QUADRIX_INSTALL_CMAKEDIR})
