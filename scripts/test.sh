#!/usr/bin/env bash
# Sets everything up on a fresh Debian 12 machine, builds, and runs the whole
# test suite with ctest. Exits non-zero on any failure. Tests that need the data
# in ../shared skip, saying what is missing, when it is absent.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

agex_install_dependencies
agex_build -DAGEX_BUILD_TESTS=ON
ctest --test-dir "$AGEX_BUILD_DIR" --output-on-failure -j "$AGEX_JOBS"
