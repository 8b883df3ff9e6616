# Installs agexConfig.cmake, agexConfigVersion.cmake and agexTargets.cmake so that
#   find_package(agex 0.1 REQUIRED)
#   target_link_libraries(app PRIVATE agex::keypoints)   # or agex::agex for everything
# works from another project. The modules add themselves to the agexTargets export
# (agex_add_module); the bundled model and frame go to <prefix>/share/agex.
include(CMakePackageConfigHelpers)

set(AGEX_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/agex CACHE STRING
    "Where agexConfig.cmake is installed, relative to the prefix")

install(EXPORT agexTargets NAMESPACE agex:: FILE agexTargets.cmake DESTINATION ${AGEX_INSTALL_CMAKEDIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/agexConfig.cmake.in
  ${PROJECT_BINARY_DIR}/agexConfig.cmake INSTALL_DESTINATION ${AGEX_INSTALL_CMAKEDIR}
  PATH_VARS CMAKE_INSTALL_INCLUDEDIR CMAKE_INSTALL_DATADIR)
# 0.x releases break the API between minor versions, so 0.1 accepts only 0.1.*.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/agexConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/agexConfig.cmake ${PROJECT_BINARY_DIR}/agexConfigVersion.cmake
  DESTINATION ${AGEX_INSTALL_CMAKEDIR})

install(FILES ${PROJECT_SOURCE_DIR}/data/models/agex_bonn.yml ${PROJECT_SOURCE_DIR}/data/models/agex_bonn_sw.yml
  ${PROJECT_SOURCE_DIR}/data/models/agex_bonn_agex.yml ${PROJECT_SOURCE_DIR}/data/models/agex_bonn_forest.agexforest
  ${PROJECT_SOURCE_DIR}/data/models/LICENSE.bonn-data ${PROJECT_SOURCE_DIR}/data/models/LICENSE.agex_bonn
  ${PROJECT_SOURCE_DIR}/data/models/agex_synthetic_forest.agexforest
  ${PROJECT_SOURCE_DIR}/data/models/LICENSE.agex_synthetic_forest DESTINATION ${CMAKE_INSTALL_DATADIR}/agex/models)
if(TARGET agex_landmarks_lib)
  install(FILES ${PROJECT_SOURCE_DIR}/data/models/agex_contour_landmarks.dat
    ${PROJECT_SOURCE_DIR}/data/models/LICENSE.agex_contour_landmarks
    ${PROJECT_SOURCE_DIR}/data/models/agex_people_detector.svm
    ${PROJECT_SOURCE_DIR}/data/models/LICENSE.agex_people_detector DESTINATION ${CMAKE_INSTALL_DATADIR}/agex/models)
  install(FILES ${PROJECT_SOURCE_DIR}/data/images/five_people.jpg ${PROJECT_SOURCE_DIR}/data/images/LICENSE.pcl-test-data
    DESTINATION ${CMAKE_INSTALL_DATADIR}/agex/images)
endif()
install(FILES ${PROJECT_SOURCE_DIR}/data/frames/bonn_1_002.png ${PROJECT_SOURCE_DIR}/data/frames/LICENSE.bonn
  DESTINATION ${CMAKE_INSTALL_DATADIR}/agex/frames)
