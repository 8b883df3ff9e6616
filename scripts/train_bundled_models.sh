#!/usr/bin/env bash
# Retrains the bundled depth models in data/models from the Bonn frames in ../shared
# (doc/results.md, "The bundled models"): the body-part forest, the fused detector (its
# classifier trained on forest features cross-fitted over four groups of sequences), the
# AGEX-point model and the sliding-window baseline, each on both views of all 8 sequences.
# Takes about half an hour on 2 cores. Usage: scripts/train_bundled_models.sh [BUILD_DIR] [WORK_DIR]
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BIN="${1:-$ROOT/build}/bin"
WORK="${2:-$(mktemp -d)}"
BONN="$ROOT/../shared/data/bonn"
MODELS="$ROOT/data/models"
[ -d "$BONN" ] || { echo "train_bundled_models: $BONN is missing (the Bonn frames of ../shared)" >&2; exit 1; }
for view in portrait full; do
  [ -d "$WORK/bonn-$view" ] || "$BIN/agex_convert" bonn --input "$BONN" --output "$WORK/bonn-$view" --view "$view"
done
both () { echo --dataset "$WORK/bonn-full@$1" --dataset "$WORK/bonn-portrait@$1"; }
FOREST_FLAGS=(--hand-reach 0.12 --threads 2)
RECIPE=(--k 16 --weak-count 200 --fragments 100 --random-negatives 3)
ALL=1,2,3,4,5,6,7,8
"$BIN/agex_train_forest" $(both $ALL) "${FOREST_FLAGS[@]}" --out "$MODELS/agex_bonn_forest.agexforest"
# Cross-fitting: each group's frames are labelled by a forest trained without them.
fold_args=()
for group in 1,2 3,4 5,6 7,8; do
  rest=$(echo $ALL | tr ',' '\n' | grep -vxF -f <(echo $group | tr ',' '\n') | paste -sd,)
  "$BIN/agex_train_forest" $(both $rest) "${FOREST_FLAGS[@]}" --out "$WORK/forest_without_${group//,/}.agexforest"
  for view in full portrait; do
    fold_args+=(--dataset "$WORK/bonn-$view@$group" --dataset-forest "$WORK/bonn-$view@$group=$WORK/forest_without_${group//,/}.agexforest")
  done
done
"$BIN/agex_train" --fused --forest "$MODELS/agex_bonn_forest.agexforest" "${fold_args[@]}" "${RECIPE[@]}" --out "$MODELS/agex_bonn.yml"
"$BIN/agex_train" $(both $ALL) "${RECIPE[@]}" --out "$MODELS/agex_bonn_agex.yml"
"$BIN/agex_train" --sliding-window $(both $ALL) --weak-count 300 --fragments 150 --out "$MODELS/agex_bonn_sw.yml"
