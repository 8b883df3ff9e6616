# AGEX_SANITIZE=ON: everything (libraries, apps, tests) is built with AddressSanitizer
# (LeakSanitizer included) and UndefinedBehaviorSanitizer. Undefined behaviour aborts
# (-fno-sanitize-recover) so that a test hitting it fails instead of printing a warning.
# Runtime options and suppressions: test/sanitizers/, compiled into every executable
# (agex_use_sanitizer_defaults below).
if(AGEX_SANITIZE)
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

# AGEX_BUILD_FUZZERS=ON: everything gets libFuzzer's coverage instrumentation and the
# sanitizers, so that the fuzzers (test/fuzz) see into the readers they call. Line tables
# (coming after the build type's -g, they replace it) are all a report's stack needs, and
# cheaper to compile and link than full debug information of PCL's templates.
if(AGEX_BUILD_FUZZERS)
  if(NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    message(FATAL_ERROR "AGEX_BUILD_FUZZERS needs clang (libFuzzer), e.g. -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_C_COMPILER=clang")
  endif()
  if(NOT AGEX_BUILD_TESTS)
    message(FATAL_ERROR "AGEX_BUILD_FUZZERS needs AGEX_BUILD_TESTS=ON (the fuzzers live in test/fuzz)")
  endif()
  add_compile_options(-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined
                      -fno-omit-frame-pointer -gline-tables-only -DEIGEN_MALLOC_ALREADY_ALIGNED=1)  # see above
  add_link_options(-fsanitize=address,undefined)
endif()

# agex_use_sanitizer_defaults(<executable>): in a sanitizer build, compiles the runtime
# settings and suppressions of test/sanitizers into the executable.
function(agex_use_sanitizer_defaults target)
  if(AGEX_SANITIZE OR AGEX_BUILD_FUZZERS)
    target_sources(${target} PRIVATE ${PROJECT_SOURCE_DIR}/test/sanitizers/sanitizer_defaults.cpp)
    set_source_files_properties(${PROJECT_SOURCE_DIR}/test/sanitizers/sanitizer_defaults.cpp PROPERTIES
      COMPILE_DEFINITIONS AGEX_SANITIZER_DIR="${PROJECT_SOURCE_DIR}/test/sanitizers")
  endif()
endfunction()
