#!/usr/bin/env bash
# Splits ../shared's motion-capture pose sources by CMU subject into a training and a held-out
# part, as folders of symbolic links that agex_synth --pose-dir reads: a synthetic test set
# drawn from the held-out part shows poses (and performers) no training frame showed.
# Held out: cmu_cc subject 006 (14 of 61 clips); cmu_poses subjects 13, 62, 69, 76, 90, 111 and
# 139 (20 of 105 clips). The five clips (cmu_02_01 ... cmu_131_03) are training clips.
#   scripts/pose_split.sh OUT_DIR    -> OUT_DIR/{train,test}/{cmu_cc,cmu_poses}
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
M="$ROOT/../shared/data/mocap"
OUT=${1:?usage: pose_split.sh OUT_DIR}
for need in "$M/cmu_cc" "$M/cmu_poses"; do
  [ -d "$need" ] || { echo "pose_split: $need is missing (see ../shared/README.md)" >&2; exit 1; }
done
held_out () {  # source subject -> 0 if held out
  case "$1:$((10#$2))" in
    cmu_cc:6 | cmu_poses:13 | cmu_poses:62 | cmu_poses:69 | cmu_poses:76 | cmu_poses:90 | cmu_poses:111 | cmu_poses:139) return 0 ;;
    *) return 1 ;;
  esac
}
for source in cmu_cc cmu_poses; do
  mkdir -p "$OUT/train/$source" "$OUT/test/$source"
  for f in "$M/$source"/*.bvh; do
    name=$(basename "$f")
    part=train
    held_out "$source" "${name%%_*}" && part=test
    ln -sfn "$(cd "$(dirname "$f")" && pwd)/$name" "$OUT/$part/$source/$name"
  done
done
echo "pose_split: $(ls "$OUT"/train/*/ | grep -c bvh) training and $(ls "$OUT"/test/*/ | grep -c bvh) held-out clips in $OUT"
