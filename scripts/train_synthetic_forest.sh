#!/usr/bin/env bash
# Reproduces data/models/agex_synthetic_forest.agexforest from ../shared: a per-pixel body-part
# forest trained on synthetic frames alone (doc/results.md, "Synthetic people, real frames"):
# MakeHuman bodies of 24 sampled shapes, posed from the pose bank (CMU cc clips, the CMU
# everyday pose bank, 2,000 procedural poses, thinned at 5 cm) and from the five walking and
# dancing clips, in whole scenes and aimed portrait views, through every sensor model: Kinect v1
# at 640x480 and 320x240 (the five clips' frames with its correlation window), Kinect v2-like
# time of flight at 512x424, and the Bonn frames' 8-bit portrait view. No real frame is used.
# Takes about 14 minutes on 2 cores (rendering 5, training 9).
#   scripts/train_synthetic_forest.sh [BUILD_DIR] [WORK_DIR] [OUT]
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BIN="${1:-$ROOT/build}/bin"
WORK="${2:-$(mktemp -d)}"
OUT="${3:-$ROOT/data/models/agex_synthetic_forest.agexforest}"
SHARED="$ROOT/../shared/data"
M="$SHARED/mocap"
for need in "$M/cmu_cc" "$M/cmu_poses" "$SHARED/makehuman/targets"; do
  [ -d "$need" ] || { echo "train_synthetic_forest: $need is missing (see ../shared/README.md)" >&2; exit 1; }
done
SHAPES=(--body-mesh "$SHARED/makehuman" --body-shapes --subjects 24)
BANK=(--pose-dir "$M/cmu_cc" --pose-dir "$M/cmu_poses" --procedural-poses 2000 --thin-poses 0.05)
FIVE=(--motion "$M/cmu_02_01.bvh" "$M/cmu_05_06.bvh" "$M/cmu_131_01.bvh" "$M/cmu_131_02.bvh" "$M/cmu_131_03.bvh")
render () {
  local name=$1; shift
  [ -f "$WORK/$name/dataset.json" ] || "$BIN/agex_synth" "${SHAPES[@]}" "$@" --output "$WORK/$name" > "$WORK/$name.log"
}
# Two at a time, one per core.
( render bank_k640 "${BANK[@]}" --layout whole --people 3 --sensor kinect --frames 500 --seed 101
  render bank_k2 "${BANK[@]}" --layout whole --people 3 --sensor kinect2 --frames 200 --seed 103
  render five_k640 "${FIVE[@]}" --layout whole --people 3 --sensor kinect --kinect-window 9 --frames 300 --seed 105 ) &
first=$!
( render bank_k320 "${BANK[@]}" --layout whole --people 3 --sensor kinect --resolution 320x240 --frames 400 --seed 102
  render bank_bonn "${BANK[@]}" --sensor bonn --frames 500 --seed 104
  render five_bonn "${FIVE[@]}" --sensor bonn --frames 400 --seed 106
  render five_k320 "${FIVE[@]}" --layout whole --people 3 --sensor kinect --resolution 320x240 --kinect-window 9 \
    --frames 300 --seed 107 ) &
second=$!
wait "$first" && wait "$second" || { echo "train_synthetic_forest: rendering failed (logs in $WORK)" >&2; exit 1; }
"$BIN/agex_train_forest" $(for d in bank_k640 bank_k2 bank_k320 bank_bonn five_k640 five_bonn five_k320; do
  echo --dataset "$WORK/$d"; done) --threads 2 --out "$OUT"
