#!/usr/bin/env bash
# Retrains the bundled people detector (data/models/agex_people_detector.svm; doc/landmarks.md,
# "The people detector") from ../shared/data/people2d:
#   - the Clothing Co-Parsing photos but every fifth (0005, 0010, ..., 0900: the held-out fold,
#     which holds the 10 photos the tests use), their people as they are and pasted into each
#     other's photos, and their people-free bands (each outline grown by 0.1 of its height, cut
#     away) as images without people;
#   - INRIA's upright person crops but every fifth (crops 0, 5, 10, ... in name order: the
#     held-out fold), pasted 2 per photo into the CCP photos, people 72-200 pixels tall. The
#     crops are used for training only; they are never copied into the repository.
# fhog window 40x80, images enlarged 1.25 times before detection (people from 64 pixels up),
# C 20, left-right flips. Takes about TIME_TBD on the shared 2 cores.
# Usage: scripts/train_people_detector.sh [OUT_FILE] [BUILD_DIR] [WORK_DIR]
# (default OUT_FILE: data/models/agex_people_detector.svm; an existing detector there is replaced).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OUT="${1:-$ROOT/data/models/agex_people_detector.svm}"
BIN="${2:-$ROOT/build}/bin"
WORK="${3:-$(mktemp -d)}"
DATA="$ROOT/../shared/data/people2d"
CCP="$DATA/ccp"
INRIA="$DATA/inria_pos/images"
for need in "$CCP/photos" "$CCP/masks" "$INRIA"; do
  [ -d "$need" ] || { echo "train_people_detector: $need is missing (see ../shared/README.md)" >&2; exit 1; }
done
mkdir -p "$WORK"
HELD_OUT=$(for i in $(seq 5 5 900); do printf "%04d.jpg " "$i"; done)
# shellcheck disable=SC2086 # HELD_OUT is a list of file names
[ -f "$WORK/ccp_train.xml" ] ||
  "$BIN/agex_annotate" masks --images "$CCP/photos" --masks "$CCP/masks" --labels-excluded 2,33,56 --skip $HELD_OUT \
    --out "$WORK/ccp_train.xml"
# The shape predictor of this run is a stub (agex_landmarks_train always trains one).
"$BIN/agex_landmarks_train" --dataset "$WORK/ccp_train.xml" --out "$WORK/stub.dat" --oversampling 1 --cascade-depth 1 \
  --trees-per-level 1 --threads 1 --detector-out "$OUT" --detector-c 20 \
  --detector-crops "$INRIA" --detector-crops-box 24,32,48,96 --detector-crops-held-out 0 --detector-crops-min-height 72 --detector-crops-max-height 200 \
  --detector-backgrounds 1 --detector-window-width 40 --detector-window-height 80 --detector-scale 1.25
