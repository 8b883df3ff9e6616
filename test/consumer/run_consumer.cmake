# ctest agex_install_consumer: installs the build to a scratch prefix, then builds and
# runs doc/examples/find_body_parts (the tutorial's program, a project of its own using
# find_package(agex 0.1 REQUIRED)) against that prefix, as a PCL user would.
#   cmake -DAGEX_BINARY_DIR=.. -DAGEX_SOURCE_DIR=.. -DWORK_DIR=.. -DCXX=.. [-DCXX_FLAGS=..] -P run_consumer.cmake
foreach(var AGEX_BINARY_DIR AGEX_SOURCE_DIR WORK_DIR CXX)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "run_consumer.cmake needs -D${var}=...")
  endif()
endforeach()

function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    string(REPLACE ";" " " command "${ARGN}")
    message(FATAL_ERROR "failed (${rc}): ${command}\n${out}\n${err}")
  endif()
  set(run_output "${out}${err}" PARENT_SCOPE)
endfunction()

# Every code block of the tutorial is in the program word for word (the blocks are the
# program's lines, indented by 4 less).
# ';' and '[' ']' are list syntax to CMake: both texts get them replaced first.
function(read_for_lists path var)
  file(READ ${path} text)
  string(REPLACE ";" "<semicolon>" text "${text}")
  string(REPLACE "[" "<open>" text "${text}")
  string(REPLACE "]" "<close>" text "${text}")
  set(${var} "${text}" PARENT_SCOPE)
endfunction()
read_for_lists(${AGEX_SOURCE_DIR}/doc/tutorial.md tutorial)
read_for_lists(${AGEX_SOURCE_DIR}/doc/examples/find_body_parts/find_body_parts.cpp program)
string(REPLACE "\n    " "\n" program "${program}")
string(REGEX MATCHALL "```cpp\n[^`]*```" blocks "${tutorial}")
list(LENGTH blocks block_count)
if(block_count LESS 10)
  message(FATAL_ERROR "doc/tutorial.md: expected the 10 code blocks of the program, found ${block_count}")
endif()
foreach(block IN LISTS blocks)
  string(REGEX REPLACE "^```cpp\n" "" code "${block}")
  string(REGEX REPLACE "```$" "" code "${code}")
  string(FIND "${program}" "${code}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "doc/tutorial.md has code that is not in find_body_parts.cpp:\n${code}")
  endif()
endforeach()

set(prefix ${WORK_DIR}/prefix)
file(REMOVE_RECURSE ${WORK_DIR})
run(${CMAKE_COMMAND} --install ${AGEX_BINARY_DIR} --prefix ${prefix})

# What a user relies on is there.
file(GLOB config ${prefix}/lib*/cmake/agex/agexConfig.cmake ${prefix}/lib/*/cmake/agex/agexConfig.cmake)
if(NOT config)
  message(FATAL_ERROR "no agexConfig.cmake installed under ${prefix}")
endif()
get_filename_component(config_dir "${config}" DIRECTORY)
foreach(file include/agex/keypoints/agex_keypoint.h include/agex/keypoints/impl/agex_keypoint.hpp
             include/agex/io/frame_io.h bin/agex_detect share/agex/models/agex_bonn.yml
             share/agex/models/agex_bonn_agex.yml share/agex/models/agex_bonn_forest.agexforest
             share/agex/models/agex_bonn_sw.yml)
  if(NOT EXISTS ${prefix}/${file})
    message(FATAL_ERROR "${file} was not installed")
  endif()
endforeach()

# Version file: 0.1 asks are met, 0.2 and 1.0 asks are not.
foreach(asked_compatible 0.1:TRUE 0.1.0:TRUE 0.2:FALSE 1.0:FALSE)
  string(REPLACE ":" ";" pair ${asked_compatible})
  list(GET pair 0 PACKAGE_FIND_VERSION)
  list(GET pair 1 expected)
  string(REPLACE "." ";" parts ${PACKAGE_FIND_VERSION})
  list(GET parts 0 PACKAGE_FIND_VERSION_MAJOR)
  list(GET parts 1 PACKAGE_FIND_VERSION_MINOR)
  set(PACKAGE_VERSION_COMPATIBLE FALSE)
  include(${config_dir}/agexConfigVersion.cmake)
  if(NOT "${PACKAGE_VERSION_COMPATIBLE}" STREQUAL "${expected}")
    message(FATAL_ERROR "asking for agex ${PACKAGE_FIND_VERSION} gave compatible=${PACKAGE_VERSION_COMPATIBLE}")
  endif()
endforeach()

# A project of its own, against the installed copy only.
run(${CMAKE_COMMAND} -S ${AGEX_SOURCE_DIR}/doc/examples/find_body_parts -B ${WORK_DIR}/build
    -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_CXX_COMPILER=${CXX}
    "-DCMAKE_CXX_FLAGS=${CXX_FLAGS}")
run(${CMAKE_COMMAND} --build ${WORK_DIR}/build)
run(${WORK_DIR}/build/find_body_parts ${prefix}/share/agex/frames/bonn_1_002.png
    ${prefix}/share/agex/models/agex_bonn_agex.yml ${prefix}/share/agex/models/agex_bonn.yml)
message("${run_output}")
foreach(expected "frame: 640 x 480 points" "AGEX points: [1-9]" ": head " "detection: head at pixel")
  if(NOT run_output MATCHES "${expected}")
    message(FATAL_ERROR "find_body_parts output does not match '${expected}'")
  endif()
endforeach()

# to_millionths(TEXT OUT): a non-negative decimal number ("0.99708", "1.0", "4.1e-05") as
# whole millionths, truncated.
function(to_millionths text out)
  if(NOT text MATCHES "^([0-9]+)(\\.([0-9]*))?([eE]([-+]?[0-9]+))?$")
    message(FATAL_ERROR "not a number: '${text}'")
  endif()
  set(whole "${CMAKE_MATCH_1}")
  set(digits "${CMAKE_MATCH_1}${CMAKE_MATCH_3}")
  set(exponent "${CMAKE_MATCH_5}")
  if(exponent STREQUAL "")
    set(exponent 0)
  endif()
  string(LENGTH "${whole}" point)
  math(EXPR keep "${point} + ${exponent} + 6")
  if(keep LESS_EQUAL 0)
    set(${out} 0 PARENT_SCOPE)
    return()
  endif()
  string(APPEND digits "0000000000000000")
  string(SUBSTRING "${digits}" 0 ${keep} digits)
  string(REGEX REPLACE "^0+([0-9])" "\\1" digits "${digits}")
  set(${out} ${digits} PARENT_SCOPE)
endfunction()

# The tutorial's BodyPartDetector (step 7) and the installed agex_detect give the same
# detections: class, pixel and confidence to 1e-6.
set(program_output "${run_output}")
run(${prefix}/bin/agex_detect ${prefix}/share/agex/frames/bonn_1_002.png --json ${WORK_DIR}/detect.json)
file(READ ${WORK_DIR}/detect.json detect_json)
string(JSON count LENGTH "${detect_json}" detections)
string(REGEX MATCHALL "detection: [a-z]+ at pixel \\([0-9]+, [0-9]+\\) confidence [0-9.]+" program_lines
       "${program_output}")
list(LENGTH program_lines program_count)
if(NOT count EQUAL program_count OR count EQUAL 0)
  message(FATAL_ERROR "agex_detect found ${count} detections, the tutorial's program ${program_count}")
endif()
math(EXPR last "${count} - 1")
foreach(i RANGE ${last})
  string(JSON cls GET "${detect_json}" detections ${i} class)
  string(JSON u GET "${detect_json}" detections ${i} pixel 0)
  string(JSON v GET "${detect_json}" detections ${i} pixel 1)
  string(JSON confidence GET "${detect_json}" detections ${i} confidence)
  list(GET program_lines ${i} line)
  string(REGEX REPLACE "detection: ([a-z]+) at pixel \\(([0-9]+), ([0-9]+)\\) confidence ([0-9.]+)" "\\1;\\2;\\3;\\4"
         fields "${line}")
  list(GET fields 0 p_cls)
  list(GET fields 1 p_u)
  list(GET fields 2 p_v)
  list(GET fields 3 p_confidence)
  # Confidences to 1e-6: compare them as whole millionths (CMake has no floating point).
  to_millionths ("${confidence}" a)
  to_millionths ("${p_confidence}" b)
  math(EXPR difference "${a} - ${b}")
  if(NOT cls STREQUAL p_cls OR NOT u EQUAL p_u OR NOT v EQUAL p_v OR difference GREATER 1 OR difference LESS -1)
    message(FATAL_ERROR "detection ${i}: agex_detect ${cls} (${u}, ${v}) ${confidence}, "
                        "the tutorial's program ${p_cls} (${p_u}, ${p_v}) ${p_confidence}")
  endif()
endforeach()
message("agex_detect and the tutorial's BodyPartDetector agree on all ${count} detections")

# A consumer of agex::filters alone links no renderer, no dlib, no image codecs and no JSON
# library (ldd), and no nlohmann symbol ends up in it (nm).
run(${CMAKE_COMMAND} -S ${AGEX_SOURCE_DIR}/test/consumer/filters_only -B ${WORK_DIR}/filters_only
    -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_CXX_COMPILER=${CXX}
    "-DCMAKE_CXX_FLAGS=${CXX_FLAGS}")
run(${CMAKE_COMMAND} --build ${WORK_DIR}/filters_only)
run(${WORK_DIR}/filters_only/filters_only)
run(ldd ${WORK_DIR}/filters_only/filters_only)
set(ldd_output "${run_output}")
if(NOT ldd_output MATCHES "libagex_filters")
  message(FATAL_ERROR "the filters-only consumer does not link libagex_filters:\n${ldd_output}")
endif()
foreach(unwanted libdlib libagex_simulation libagex_io libagex_detection libagex_landmarks libopencv_imgcodecs)
  if(ldd_output MATCHES "${unwanted}")
    message(FATAL_ERROR "a consumer of agex::filters alone links ${unwanted}:\n${ldd_output}")
  endif()
endforeach()
file(GLOB filters_library ${prefix}/lib*/libagex_filters.so.* ${prefix}/lib/*/libagex_filters.so.*)
run(nm -C --defined-only ${WORK_DIR}/filters_only/filters_only ${filters_library})
if(run_output MATCHES "nlohmann")
  message(FATAL_ERROR "nlohmann (JSON) symbols in a consumer of agex::filters alone")
endif()
message("a consumer of agex::filters alone links no renderer, dlib, image codec or JSON library")

# The installed app finds the installed libraries (RPATH) and the installed model.
run(${prefix}/bin/agex_detect --help)
if(NOT run_output MATCHES "share/agex/models/agex_bonn.yml")
  message(FATAL_ERROR "the installed agex_detect does not default to the installed model:\n${run_output}")
endif()
file(REMOVE_RECURSE ${WORK_DIR})
