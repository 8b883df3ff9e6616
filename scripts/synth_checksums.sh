#!/bin/bash
# Renders a small fixed set of agex_synth datasets (capsule and mesh bodies, every sensor,
# colour) and prints the sha256 of every file written, so two builds can be compared byte
# for byte (doc/synthetic.md, "Determinism"):
#   scripts/synth_checksums.sh build/bin/agex_synth /tmp/synth-a > a.sha256
#   scripts/synth_checksums.sh other/agex_synth /tmp/synth-b > b.sha256 && diff a.sha256 b.sha256
# Extra arguments are passed to every run (e.g. --people 3). OUTDIR is replaced.
set -euo pipefail
if [ $# -lt 2 ]; then
  echo "usage: $0 AGEX_SYNTH OUTDIR [agex_synth options...]" >&2
  exit 2
fi
BIN=$(realpath "$1"); OUT=$2; shift 2
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
DATA=$(realpath "${AGEX_SHARED_DATA:-$ROOT/../shared/data}")
M=$DATA/mocap
MH=$DATA/makehuman
rm -rf "$OUT"
mkdir -p "$OUT"
run () { nice "$BIN" "$@" > /dev/null 2>&1 || { echo "$0: failed: agex_synth $*" >&2; exit 1; }; }
for sensor in sr4000 kinect bonn; do
  run --motion $M/cmu_131_01.bvh $M/cmu_02_01.bvh $M/cmu_05_06.bvh --frames 6 --sensor $sensor --seed 7 \
      --output "$OUT/capsule_$sensor" "$@"
  run --motion $M/cmu_131_03.bvh $M/cmu_02_01.bvh --frames 4 --sensor $sensor --seed 11 --body-mesh $MH \
      --output "$OUT/mesh_$sensor" "$@"
done
run --motion $M/cmu_131_01.bvh --frames 3 --sensor kinect --seed 5 --colour --output "$OUT/colour_kinect" "$@"
run --motion $M/cmu_131_01.bvh --frames 3 --sensor sr4000 --seed 5 --colour --body-mesh $MH \
    --output "$OUT/colour_mesh_sr4000" "$@"
cd "$OUT" && find . -type f | LC_ALL=C sort | xargs sha256sum
