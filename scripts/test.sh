#!/usr/bin/env bash
# Sets everything up on a fresh Debian 12 machine, builds, and runs the whole
# test suite with ctest, three times over:
#   build/       the Release build, every test;
#   build-asan/  every test again with AddressSanitizer (leaks included) and
#                UndefinedBehaviorSanitizer (AGEX_SANITIZE=ON; skip with AGEX_SKIP_SANITIZE=1);
#   build-fuzz/  each fuzz target on AGEX_FUZZ_RUNS (default 20000) inputs from a fixed seed,
#                at most AGEX_FUZZ_SECONDS (60) seconds, when clang
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

if [ "${AGEX_SKIP_SANITIZE:-0}" != 1 ]; then
  echo "agex: the whole suite again under AddressSanitizer + UndefinedBehaviorSanitizer"
  AGEX_BUILD_DIR="$AGEX_ROOT/build-asan" agex_build -DAGEX_BUILD_TESTS=ON -DAGEX_SANITIZE=ON
  stage "the sanitizer build"
  ctest --test-dir "$AGEX_ROOT/build-asan" --output-on-failure -j "$AGEX_JOBS"
  stage "the sanitizer tests"
fi

if [ "${AGEX_SKIP_FUZZ:-0}" != 1 ]; then
  if command -v clang++ >/dev/null && command -v clang >/dev/null; then
    echo "agex: fuzzing each reader: ${AGEX_FUZZ_RUNS:-20000} seeded inputs (at most ${AGEX_FUZZ_SECONDS:-60} s)"
    cmake -S "$AGEX_ROOT" -B "$AGEX_ROOT/build-fuzz" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
      -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DAGEX_BUILD_FUZZERS=ON \
      -DAGEX_BUILD_APPS=OFF -DAGEX_FUZZ_SECONDS="${AGEX_FUZZ_SECONDS:-60}" \
      -DAGEX_FUZZ_RUNS="${AGEX_FUZZ_RUNS:-20000}" >/dev/null
    cmake --build "$AGEX_ROOT/build-fuzz" --target agex_fuzzers -j "$AGEX_JOBS"
    stage "the fuzzer build"
    ctest --test-dir "$AGEX_ROOT/build-fuzz" -L '^fuzz$' --output-on-failure -j "$AGEX_JOBS"
    stage "fuzzing"
  else
    echo "agex: clang not found, fuzzers not run (the kept crashers were replayed above)"
  fi
fi
