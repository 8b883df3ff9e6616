# agex_add_module(<name> SOURCES ... DEPENDS ...)
# One shared library per module, libagex_<name>.so.<major>.<minor>, with its public headers
# in <module>/include. Use it as agex::<name> (the target itself is agex_<name>_lib so
# that apps may be called agex_<name>). Include directories of dependencies come from
# their targets (PCL's, OpenCV's), so no absolute path of this machine is exported.
function(agex_add_module name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPENDS" ${ARGN})
  set(target agex_${name}_lib)
  add_library(${target} SHARED ${ARG_SOURCES})
  add_library(agex::${name} ALIAS ${target})
  target_include_directories(${target} PUBLIC
    $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
    $<INSTALL_INTERFACE:include>)
  target_compile_definitions(${target} PUBLIC ${PCL_DEFINITIONS})
  target_link_libraries(${target} PUBLIC ${ARG_DEPENDS})
  target_compile_options(${target} PRIVATE -Wall -Wextra)
  agex_use_precompiled_headers(${target})
  agex_use_fuzzer_coverage(${target} SOURCES ${ARG_SOURCES})
  set_target_properties(${target} PROPERTIES OUTPUT_NAME agex_${name} EXPORT_NAME ${name}
    VERSION ${PROJECT_VERSION} SOVERSION ${PROJECT_VERSION_MAJOR}.${PROJECT_VERSION_MINOR})
  # Installed as agex::<name> through agexConfig.cmake (top-level CMakeLists.txt), headers
  # (impl/*.hpp included) under <prefix>/include/agex/<name>.
  install(TARGETS ${target} EXPORT agexTargets
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
    RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  install(DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
    FILES_MATCHING PATTERN "*.h" PATTERN "*.hpp")
endfunction()

# agex_add_app(<name> SOURCES ... DEPENDS ...): an executable in <build>/bin.
function(agex_add_app name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPENDS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_DEPENDS})
  target_compile_options(${name} PRIVATE -Wall -Wextra)
  agex_use_sanitizer_defaults(${name})
  agex_use_precompiled_headers(${name})
  install(TARGETS ${name} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endfunction()
