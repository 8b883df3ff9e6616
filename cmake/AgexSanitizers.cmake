# AGEX_SANITIZE=ON: everything (libraries, apps, tests) is built with AddressSanitizer
# (LeakSanitizer included) and UndefinedBehaviorSanitizer. Undefined behaviour aborts
# (-fno-sanitize-recover) so that a test hitting it fails instead of printing a warning.
# Runtime options and suppressions: test/sanitizers/, compiled into every executable
# (agex_use_sanitizer_defaults below). AGEX_BUILD_FUZZERS (below) implies the same.
if(AGEX_SANITIZE OR AGEX_BUILD_FUZZERS)
  # EIGEN_MALLOC_ALREADY_ALIGNED=1: Eigen switches to its own aligned allocator when it sees
  # AddressSanitizer (__SANITIZE_ADDRESS__), which then frees memory that the system PCL (built
  # without it) allocated with plain malloc: a false heap-buffer-overflow in every cloud passed
  # across. Keeping the system's allocator choice keeps the two ABI compatible.
  set(AGEX_SANITIZER_FLAGS -fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer
      -DEIGEN_MALLOC_ALREADY_ALIGNED=1)
  add_compile_options(${AGEX_SANITIZER_FLAGS})
  add_link_options(-fsanitize=address,undefined)
  # For projects built against this build (test/consumer), which must link the runtimes too.
  string(REPLACE ";" " " AGEX_SANITIZER_FLAGS_STRING "${AGEX_SANITIZER_FLAGS}")
endif()

# AGEX_BUILD_FUZZERS=ON: everything gets the sanitizers, as with AGEX_SANITIZE, so that one
# clang build serves both the sanitizer suite and the fuzzers (test.sh). libFuzzer's coverage
# instrumentation (-fsanitize=fuzzer-no-link: a call on every comparison) goes only where the
# fuzzers' input goes, the sources of AGEX_FUZZED_SOURCES and the fuzz targets: everywhere, it
# made the renderer's and the trainers' tests forty times slower than in Release. Line tables
# (coming after the build type's -g, they replace it) are all a report's stack needs, and
# cheaper to compile and link than full debug information of PCL's templates.
set(AGEX_FUZZED_SOURCES common/src io/src classification/src/patch_classifier.cpp
    landmarks/src/imglab_dataset.cpp CACHE STRING
    "Sources (files or folders, from the source root) compiled with libFuzzer's coverage instrumentation when AGEX_BUILD_FUZZERS=ON")
if(AGEX_BUILD_FUZZERS)
  if(NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    message(FATAL_ERROR "AGEX_BUILD_FUZZERS needs clang (libFuzzer), e.g. -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_C_COMPILER=clang")
  endif()
  if(NOT AGEX_BUILD_TESTS)
    message(FATAL_ERROR "AGEX_BUILD_FUZZERS needs AGEX_BUILD_TESTS=ON (the fuzzers live in test/fuzz)")
  endif()
  add_compile_options(-gline-tables-only)
endif()

# agex_use_fuzzer_coverage(<target> [SOURCES <file>...]): with AGEX_BUILD_FUZZERS, compiles
# <target> (or those of its sources that AGEX_FUZZED_SOURCES names) with libFuzzer's coverage
# instrumentation. Call it from the directory that creates the target.
function(agex_use_fuzzer_coverage target)
  cmake_parse_arguments(ARG "" "" "SOURCES" ${ARGN})
  if(NOT AGEX_BUILD_FUZZERS)
    return()
  endif()
  if(NOT ARG_SOURCES)
    target_compile_options(${target} PRIVATE -fsanitize=fuzzer-no-link)
    return()
  endif()
  foreach(source IN LISTS ARG_SOURCES)
    get_filename_component(path ${source} ABSOLUTE)
    file(RELATIVE_PATH path ${PROJECT_SOURCE_DIR} ${path})
    foreach(fuzzed IN LISTS AGEX_FUZZED_SOURCES)
      if(path STREQUAL fuzzed OR path MATCHES "^${fuzzed}/")
        set_property(SOURCE ${source} APPEND PROPERTY COMPILE_OPTIONS -fsanitize=fuzzer-no-link)
      endif()
    endforeach()
  endforeach()
endfunction()

# agex_use_sanitizer_defaults(<executable>): in a sanitizer build, compiles the runtime
# settings and suppressions of test/sanitizers into the executable.
function(agex_use_sanitizer_defaults target)
  if(AGEX_SANITIZE OR AGEX_BUILD_FUZZERS)
    target_sources(${target} PRIVATE ${PROJECT_SOURCE_DIR}/test/sanitizers/sanitizer_defaults.cpp)
    set_source_files_properties(${PROJECT_SOURCE_DIR}/test/sanitizers/sanitizer_defaults.cpp PROPERTIES
      COMPILE_DEFINITIONS AGEX_SANITIZER_DIR="${PROJECT_SOURCE_DIR}/test/sanitizers")
  endif()
endfunction()
