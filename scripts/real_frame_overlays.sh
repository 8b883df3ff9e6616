#!/usr/bin/env bash
# Overlays and a summary of a detector model on the real frames without labels (doc/results.md,
# "Real frames without labels"): PCL's five_people.pcd (five people walking away, 1.8-2.8 m)
# and Skeltrack's six close upper bodies (0.7-2 m), at confidence 0.3.
#   scripts/real_frame_overlays.sh OUT_DIR [MODEL] [BUILD_DIR]
# Writes OUT_DIR/<frame>.png (the detections over the depth) and <frame>.json, and prints per
# frame the persons and the detections per class, and any hand within 0.15 m of a head.
# OUT_DIR must be new or an earlier real_frame_overlays folder.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OUT=${1:?usage: real_frame_overlays.sh OUT_DIR [MODEL] [BUILD_DIR]}
MODEL=${2:-$ROOT/data/models/agex_bonn.yml}
BIN="${3:-$ROOT/build}/bin"
KINECT="$ROOT/../shared/data/kinect"
[ -d "$KINECT/skeltrack" ] && [ -f "$KINECT/five_people.pcd" ] ||
  { echo "real_frame_overlays: $KINECT (five_people.pcd, skeltrack/) is missing (see ../shared/README.md)" >&2; exit 1; }
if [ -d "$OUT" ] && [ -n "$(ls -A "$OUT")" ] && [ ! -e "$OUT/.real_frame_overlays" ]; then
  echo "real_frame_overlays: $OUT exists and is not an earlier real_frame_overlays folder" >&2; exit 1
fi
[ -e "$OUT" ] && [ ! -d "$OUT" ] && { echo "real_frame_overlays: $OUT is a file" >&2; exit 1; }
mkdir -p "$OUT" && touch "$OUT/.real_frame_overlays"
frames=("$KINECT/five_people.pcd")
shopt -s nullglob
for f in "$KINECT"/skeltrack/depth-data-*.u16; do frames+=("$f"); done
shopt -u nullglob
for f in "${frames[@]}"; do
  name=$(basename "${f%.*}")
  "$BIN/agex_detect" "$f" --model "$MODEL" --min-confidence 0.3 --overlay "$OUT/$name.png" --json "$OUT/$name.json" \
    > "$OUT/$name.log" 2>&1 || { echo "real_frame_overlays: agex_detect failed on $f (log: $OUT/$name.log)" >&2; exit 1; }
  python3 - "$OUT/$name.json" "$name" <<'PY'
import json, math, sys
doc = json.load(open(sys.argv[1]))
dets = [d for d in doc["detections"] if d["confidence"] >= 0.3]
count = {c: sum(d["class"] == c for d in dets) for c in ("head", "hand", "foot")}
heads = [d for d in dets if d["class"] == "head"]
on_head = [d for d in dets if d["class"] == "hand" and any(math.dist(d["position"], h["position"]) < 0.15 for h in heads)]
print(f"{sys.argv[2]}: {len(doc['persons'])} persons at "
      + ", ".join(f"{p['distance']:.2f}" for p in sorted(doc["persons"], key=lambda p: p["distance"]))
      + f" m; heads {count['head']}, hands {count['hand']}, feet {count['foot']} at 0.3"
      + (f"; {len(on_head)} hand(s) within 0.15 m of a head" if on_head else ""))
PY
done
