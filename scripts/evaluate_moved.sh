#!/usr/bin/env bash
# Scores detector models on held-out Bonn sequences re-projected to other distances
# (doc/results.md, "Every distance"): the keyframes of the test sequences moved so that the
# person stands at 3, 4 and 5 m (two copies each, +-0.6 m sideways; the recorded floor extended
# as a plane), seen by the 640x480 Kinect and in the Bonn portrait view (Kinect depth, no 8-bit
# levels), then agex_eval detect per model: AP per class at 10 cm and person recall.
#   scripts/evaluate_moved.sh OUT_DIR SEQS MODEL... [-- BUILD_DIR]
# MODEL: a detector model file, or "pcl" for PCL's forests in forest mode.
# Example: scripts/evaluate_moved.sh /tmp/moved 7,8 data/models/agex_bonn.yml data/models/agex_bonn_sw.yml pcl
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OUT=${1:?usage: evaluate_moved.sh OUT_DIR SEQS MODEL... [-- BUILD_DIR]}
SEQS=${2:?usage: evaluate_moved.sh OUT_DIR SEQS MODEL... [-- BUILD_DIR]}
shift 2
models=()
BUILD="$ROOT/build"
while [ $# -gt 0 ]; do
  if [ "$1" = "--" ]; then BUILD=$2; break; fi
  models+=("$1"); shift
done
[ ${#models[@]} -gt 0 ] || { echo "evaluate_moved: no model given" >&2; exit 1; }
BIN="$BUILD/bin"
SHARED="$ROOT/../shared/data"
[ -d "$SHARED/bonn" ] || { echo "evaluate_moved: $SHARED/bonn is missing (the Bonn frames of ../shared)" >&2; exit 1; }
# OUT_DIR is this script's own: an existing folder of other things is refused, never written into.
if [ -d "$OUT" ] && [ -n "$(ls -A "$OUT")" ] && [ ! -e "$OUT/.evaluate_moved" ]; then
  echo "evaluate_moved: $OUT exists and is not an earlier evaluate_moved folder" >&2; exit 1
fi
[ -e "$OUT" ] && [ ! -d "$OUT" ] && { echo "evaluate_moved: $OUT is a file" >&2; exit 1; }
mkdir -p "$OUT" && touch "$OUT/.evaluate_moved"
[ -d "$OUT/bonn-full" ] || "$BIN/agex_convert" bonn --input "$SHARED/bonn" --output "$OUT/bonn-full" --view full \
  --sequences "$SEQS" > /dev/null
for d in 3 4 5; do
  [ -d "$OUT/kinect_${d}m" ] || "$BIN/agex_reproject" --dataset "$OUT/bonn-full@$SEQS" --keyframes-only --distance "$d" \
    --sideways 0.6 --copies 2 --sensor kinect --seed 1 --output "$OUT/kinect_${d}m" > "$OUT/kinect_${d}m.log"
  [ -d "$OUT/portrait_${d}m" ] || "$BIN/agex_reproject" --dataset "$OUT/bonn-full@$SEQS" --keyframes-only --distance "$d" \
    --sideways 0.6 --copies 2 --sensor bonn --bonn-depth-levels 0 --seed 1 --output "$OUT/portrait_${d}m" > "$OUT/portrait_${d}m.log"
done
echo "| model | view | distance | head AP | hand AP | foot AP | person recall |"
echo "| --- | --- | --- | --- | --- | --- | --- |"
for model in "${models[@]}"; do
  if [ "$model" = pcl ]; then
    flags=(--model "$ROOT/data/models/agex_bonn_agex.yml" --detector-mode forest --forest "$SHARED/pcl_people")
    name=pcl
  else
    flags=(--model "$model")
    name=$(basename "$model" .yml)
  fi
  for view in kinect portrait; do
    for d in 3 4 5; do
      json="$OUT/${name}_${view}_${d}m.json"
      "$BIN/agex_eval" detect --dataset "$OUT/${view}_${d}m" "${flags[@]}" --json "$json" > "${json%.json}.log" 2>&1
      python3 - "$json" "$name" "$view" "$d" <<'PY'
import json, sys
j = json.load(open(sys.argv[1])); ap = j["ap"]; people = j.get("people", {})
print(f"| {sys.argv[2]} | {sys.argv[3]} | {sys.argv[4]} m | {ap['head']:.3f} | {ap['hand']:.3f} | {ap['foot']:.3f} | "
      f"{people.get('person_recall', float('nan')):.3f} |")
PY
    done
  done
done
