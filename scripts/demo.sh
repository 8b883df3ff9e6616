#!/usr/bin/env bash
# Sets everything up on a fresh Debian 12 machine and runs the main job on the
# bundled Bonn frame: AGEX interest points, written to out/ as JSON and PNG.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

agex_install_dependencies
agex_build -DAGEX_BUILD_TESTS=OFF

mkdir -p "$AGEX_ROOT/out"
"$AGEX_BUILD_DIR/bin/agex_keypoints" "$AGEX_ROOT/data/frames/bonn_1_002.png" \
  --json "$AGEX_ROOT/out/keypoints.json" --overlay "$AGEX_ROOT/out/keypoints.png"
echo "agex: wrote out/keypoints.json and out/keypoints.png"
