#!/usr/bin/env bash
# Scores a per-pixel body-part forest on real frames it has never seen (doc/results.md,
# "Synthetic people, real frames"): all keyframes of Bonn 1-8 at both views, forest mode
# (one detection per part mode; AP per class at 10 cm), the per-pixel recall of the weakly
# labelled head, hand and foot pixels, and part maps of a few real frames (Bonn, Skeltrack's
# close-range upper bodies, five_people.pcd).
#   scripts/evaluate_sim_to_real.sh FOREST OUT_DIR [BUILD_DIR] [WORK_DIR]
# FOREST: a .agexforest file or a folder of PCL trees. Prints one table row per view.
# AGEX_PIPELINE_MODEL: the model whose pipeline settings forest mode runs (default the
# bundled AGEX model). AGEX_FOREST_FLAGS: extra agex_eval detect flags, e.g. "--forest-input meshes --forest-parts
# modes" for forest mode as it was before PCL's way of turning labels into parts.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
FOREST=$1 OUT=$2
BIN="${3:-$ROOT/build}/bin"
WORK="${4:-$OUT/data}"
SHARED="$ROOT/../shared/data"
[ -d "$SHARED/bonn" ] || { echo "evaluate_sim_to_real: $SHARED/bonn is missing (the Bonn frames of ../shared)" >&2; exit 1; }
[ -e "$FOREST" ] || { echo "evaluate_sim_to_real: $FOREST: no such forest" >&2; exit 1; }
mkdir -p "$OUT" "$WORK"
# The pipeline's settings (person isolation, cleaning) of the bundled models; forest mode
# uses nothing else of the model.
MODEL="${AGEX_PIPELINE_MODEL:-$ROOT/data/models/agex_bonn_agex.yml}"
ALL=1,2,3,4,5,6,7,8
for view in portrait full; do
  [ -d "$WORK/bonn-$view" ] || "$BIN/agex_convert" bonn --input "$SHARED/bonn" --output "$WORK/bonn-$view" --view "$view" >/dev/null
  "$BIN/agex_eval" detect --dataset "$WORK/bonn-$view@$ALL" --keyframes --model "$MODEL" --detector-mode forest \
    --forest "$FOREST" ${AGEX_FOREST_FLAGS:-} --json "$OUT/detect_$view.json" > "$OUT/detect_$view.log" 2>&1
  "$BIN/agex_eval" parts --dataset "$WORK/bonn-$view@$ALL" --keyframes --model "$MODEL" --forest "$FOREST" \
    --json "$OUT/parts_$view.json" > "$OUT/parts_$view.log" 2>&1
done
# Part maps of real frames of other people and sensors.
mkdir -p "$OUT/part_maps"
maps () {
  local name=$1; shift
  "$BIN/agex_detect" "$@" --model "$MODEL" --detector-mode forest --forest "$FOREST" \
    --parts-overlay "$OUT/part_maps/$name.png" > /dev/null 2>&1 || echo "evaluate_sim_to_real: no part map for $name" >&2
}
maps bonn_1_002 "$ROOT/data/frames/bonn_1_002.png"
for f in "$SHARED"/kinect/skeltrack/depth-data-1028894671.u16 "$SHARED"/kinect/skeltrack/depth-data-1399145206.u16; do
  [ -f "$f" ] && maps "skeltrack_$(basename "$f" .u16)" "$f"
done
[ -f "$SHARED/kinect/five_people.pcd" ] && maps five_people "$SHARED/kinect/five_people.pcd"
python3 - "$OUT" "$FOREST" <<'PY'
import json, sys
out, forest = sys.argv[1], sys.argv[2]
print(f"forest {forest}")
print("| view | head AP | hand AP | foot AP | head px recall | hand px recall | foot px recall |")
print("| --- | --- | --- | --- | --- | --- | --- |")
for view in ("portrait", "full"):
    d = json.load(open(f"{out}/detect_{view}.json"))
    p = json.load(open(f"{out}/parts_{view}.json"))
    ap, rec = d["ap"], p["recall"]
    print(f"| {view} | {ap['head']:.3f} | {ap['hand']:.3f} | {ap['foot']:.3f} | "
          f"{rec['head']:.3f} | {rec['hand']:.3f} | {rec['foot']:.3f} |")
PY
