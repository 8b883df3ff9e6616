# AGEX_PRECOMPILED_HEADERS (GCC only): the third-party headers nearly every file includes
# (PCL's point types and clouds, Eigen, OpenCV's core, nlohmann_json) are compiled once per
# build instead of once per file; parsing them is most of a typical file's compile time.
#
# GCC uses a precompiled header only in files compiled with the same position-independence,
# and some of the executables get -fPIC from their dependencies (Qt through PCL's VTK), others
# not: so every file that uses it is compiled with -fPIC, as the shared modules are anyway. A
# file whose settings still do not match (other definitions, say) parses the headers itself:
# slower, never different. Off for clang, which refuses a precompiled header built with other
# options instead.
if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
  set(agex_pch_default ON)
else()
  set(agex_pch_default OFF)
endif()
option(AGEX_PRECOMPILED_HEADERS "Precompile the common third-party headers (GCC)" ${agex_pch_default})

set(AGEX_PCH_HEADERS
  <pcl/point_types.h> <pcl/point_cloud.h> <pcl/pcl_base.h> <pcl/common/io.h> <pcl/console/print.h>
  <Eigen/Core> <Eigen/Geometry>
  <opencv2/core.hpp>
  <nlohmann/json.hpp>)

# agex_add_precompiled_header(<name> <extra link target>... HEADERS <header>...): an object
# library that only compiles the precompiled header, with the definitions of what it links.
function(agex_add_precompiled_header name)
  cmake_parse_arguments(ARG "" "" "HEADERS" ${ARGN})
  add_library(${name} OBJECT ${PROJECT_SOURCE_DIR}/cmake/agex_pch.cpp)
  target_link_libraries(${name} PRIVATE ${PCL_COMMON_LIBRARIES} opencv_core nlohmann_json::nlohmann_json
    ${ARG_UNPARSED_ARGUMENTS})
  target_compile_definitions(${name} PRIVATE ${PCL_DEFINITIONS})
  set_target_properties(${name} PROPERTIES POSITION_INDEPENDENT_CODE ON)
  target_precompile_headers(${name} PRIVATE ${AGEX_PCH_HEADERS} ${ARG_HEADERS})
endfunction()

if(AGEX_PRECOMPILED_HEADERS)
  agex_add_precompiled_header(agex_pch)
endif()

# agex_add_test_precompiled_headers(): the GoogleTest executables' own precompiled header,
# GoogleTest's header included (its definitions would spoil the other targets' one).
function(agex_add_test_precompiled_headers)
  if(AGEX_PRECOMPILED_HEADERS AND NOT TARGET agex_pch_test)
    agex_add_precompiled_header(agex_pch_test GTest::gtest HEADERS <gtest/gtest.h>)
  endif()
endfunction()

# agex_use_precompiled_headers(<target> [TEST]): compile <target>'s C++ files with the
# precompiled headers (TEST: the GoogleTest executables' one). The headers' include
# directories are added too, so that a file the precompiled header does not fit still finds
# what the forced include names.
function(agex_use_precompiled_headers target)
  if(NOT AGEX_PRECOMPILED_HEADERS)
    return()
  endif()
  cmake_parse_arguments(ARG "TEST" "" "" ${ARGN})
  if(ARG_TEST)
    agex_add_test_precompiled_headers()
    target_precompile_headers(${target} REUSE_FROM agex_pch_test)
  else()
    target_precompile_headers(${target} REUSE_FROM agex_pch)
  endif()
  target_compile_options(${target} PRIVATE -fPIC)
  target_include_directories(${target} SYSTEM PRIVATE ${PCL_INCLUDE_DIRS} ${OpenCV_INCLUDE_DIRS}
    $<TARGET_PROPERTY:nlohmann_json::nlohmann_json,INTERFACE_INCLUDE_DIRECTORIES>)
endfunction()
