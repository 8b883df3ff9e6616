#!/usr/bin/env bash
# Sets everything up on a fresh Debian 12 machine and runs the main job on the
# bundled Bonn frame: heads, hands and feet found with the bundled model, written
# to out/ as JSON and an overlay PNG (and the AGEX interest points beside them).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

agex_install_dependencies
agex_build -DAGEX_BUILD_TESTS=OFF

mkdir -p "$AGEX_ROOT/out"
frame="$AGEX_ROOT/data/frames/bonn_1_002.png"
"$AGEX_BUILD_DIR/bin/agex_detect" "$frame" --json "$AGEX_ROOT/out/detections.json" \
  --overlay "$AGEX_ROOT/out/detections.png"
"$AGEX_BUILD_DIR/bin/agex_keypoints" "$frame" --json "$AGEX_ROOT/out/keypoints.json" \
  --overlay "$AGEX_ROOT/out/keypoints.png"
echo "agex: wrote out/detections.json, out/detections.png (body parts) and out/keypoints.json, out/keypoints.png (AGEX points)"
