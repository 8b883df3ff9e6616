#!/usr/bin/env bash
# Sets everything up on a fresh Debian 12 machine, builds, and runs the whole
# test suite with ctest, three times over:
#   build/       the Release build, every test;
#   build-asan/  every test again with AddressSanitizer (leaks included) and
#                UndefinedBehaviorSanitizer (AGEX_SANITIZE=ON; skip with AGEX_SKIP_SANITIZE=1);
#                then, from the same build, each fuzz target on AGEX_FUZZ_RUNS (default 20000)
#                inputs from a fixed seed, at most AGEX_FUZZ_SECONDS (60) seconds, when clang
#                is installed (AGEX_BUILD_FUZZERS=ON; skip with AGEX_SKIP_FUZZ=1).
# Exits non-zero on any failure. Tests that need the data in ../shared skip, saying
# what is missing, when it is absent.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

# Each stage's time is printed, so that a slow suite shows where its time goes.
stage () { echo "agex: $1 took $((SECONDS - stage_start)) s"; stage_start=$SECONDS; }
stage_start=$SECONDS
agex_install_dependencies
stage "installing the dependencies"
agex_build -DAGEX_BUILD_TESTS=ON
stage "the Release build"
ctest --test-dir "$AGEX_BUILD_DIR" --output-on-failure -j "$AGEX_JOBS"
stage "the Release tests"

# The sanitizer suite and the fuzzers share one build: with clang, build-asan/ is compiled with
# ASan + UBSan everywhere and libFuzzer's coverage where the fuzzers' input goes, so that the
# libraries are compiled once for both. -O1 as the sanitizers' authors advise: most of the
# speed of -O3 for the tests, a much shorter build. Without clang: GCC, sanitizers only.
sanitize=$([ "${AGEX_SKIP_SANITIZE:-0}" != 1 ] && echo 1 || echo 0)
fuzz=$([ "${AGEX_SKIP_FUZZ:-0}" != 1 ] && echo 1 || echo 0)
have_clang=$(command -v clang++ >/dev/null && command -v clang >/dev/null && echo 1 || echo 0)
if [ "$fuzz" = 1 ] && [ "$have_clang" = 0 ]; then
  echo "agex: clang not found, fuzzers not run (the kept crashers were replayed above)"
  fuzz=0
fi
if [ "$sanitize" = 1 ] || [ "$fuzz" = 1 ]; then
  instrumented=(-DCMAKE_BUILD_TYPE=Release "-DCMAKE_CXX_FLAGS_RELEASE=-O1 -DNDEBUG" "-DCMAKE_C_FLAGS_RELEASE=-O1 -DNDEBUG"
                -DAGEX_BUILD_TESTS=ON -DAGEX_SANITIZE="$([ "$sanitize" = 1 ] && echo ON || echo OFF)")
  if [ "$have_clang" = 1 ]; then
    instrumented+=(-DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++)
  fi
  if [ "$fuzz" = 1 ]; then
    echo "agex: fuzzing each reader: ${AGEX_FUZZ_RUNS:-20000} seeded inputs (at most ${AGEX_FUZZ_SECONDS:-60} s)"
    instrumented+=(-DAGEX_BUILD_FUZZERS=ON -DAGEX_FUZZ_SECONDS="${AGEX_FUZZ_SECONDS:-60}" -DAGEX_FUZZ_RUNS="${AGEX_FUZZ_RUNS:-20000}")
  fi
  if [ "$sanitize" = 1 ]; then
    echo "agex: the whole suite again under AddressSanitizer + UndefinedBehaviorSanitizer"
    AGEX_BUILD_DIR="$AGEX_ROOT/build-asan" agex_build "${instrumented[@]}"
  else
    cmake -S "$AGEX_ROOT" -B "$AGEX_ROOT/build-asan" "${instrumented[@]}" -DAGEX_BUILD_APPS=OFF >/dev/null
    cmake --build "$AGEX_ROOT/build-asan" --target agex_fuzzers -j "$AGEX_JOBS"
  fi
  stage "the instrumented build"
  # One ctest run for both, so that the fuzzers' single-threaded minutes fill the gaps. The
  # mesh renderings of the Bonn and SR4000 sensors are left out here (the same code as the
  # Kinect's, each over a minute under the sanitizers); the Release suite runs them.
  labels=()
  if [ "$sanitize" = 0 ]; then labels=(-L '^fuzz$'); elif [ "$fuzz" = 0 ]; then labels=(-LE '^fuzz$'); fi
  # LeakSanitizer's tracer now and then crashes at exit while a pooled worker thread is still
  # exiting, after the test has passed and before any leak check (a known race in the sanitizer
  # runtime). Only when every failure is that crash are those tests run once more, in full.
  junit="$AGEX_ROOT/build-asan/sanitizer-tests.xml"
  if ! ctest --test-dir "$AGEX_ROOT/build-asan" "${labels[@]}" -E '^Synth/.*/(bonn|sr4000)_mesh' \
      --output-on-failure -j "$AGEX_JOBS" --output-junit "$junit"; then
    python3 "$AGEX_ROOT/scripts/leak_checker_crashes.py" "$junit" || exit 1
    echo "agex: each failure above is LeakSanitizer's tracer crashing after the test passed; running those tests again"
    ctest --test-dir "$AGEX_ROOT/build-asan" --rerun-failed --output-on-failure -j "$AGEX_JOBS"
  fi
  stage "the sanitizer tests and fuzzing"
fi
