#!/usr/bin/env bash
# scripts/pose_split.sh: every clip of the pose sources lands in exactly one part, the held-out
# subjects only in test, and the links lead to the clips. Skips (77) without ../shared's mocap.
# Usage: run_pose_split.sh SOURCE_DIR WORK_DIR
set -u
src=$1 work=$2
mocap="$src/../shared/data/mocap"
[ -d "$mocap/cmu_cc" ] && [ -d "$mocap/cmu_poses" ] || { echo "SKIP: $mocap/cmu_cc or cmu_poses is missing"; exit 77; }
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
rm -rf "$work" && mkdir -p "$work" || exit 1
bash "$src/scripts/pose_split.sh" "$work/poses" > "$work/log" 2>&1 || fail "pose_split failed: $(cat "$work/log")"
for source in cmu_cc cmu_poses; do
  all=$(ls "$mocap/$source" | grep -c '\.bvh$')
  train=$(ls "$work/poses/train/$source" | grep -c '\.bvh$')
  test=$(ls "$work/poses/test/$source" | grep -c '\.bvh$')
  [ $((train + test)) = "$all" ] || fail "$source: $train + $test links for $all clips"
  [ "$test" -gt 0 ] && [ "$train" -gt "$test" ] || fail "$source: $train training, $test held out"
  both=$(comm -12 <(ls "$work/poses/train/$source") <(ls "$work/poses/test/$source") | wc -l)
  [ "$both" = 0 ] || fail "$source: $both clips in both parts"
  for f in "$work/poses/test/$source"/*.bvh; do
    cmp -s "$f" "$mocap/$source/$(basename "$f")" || fail "$f does not lead to its clip"
    break
  done
done
ls "$work/poses/train/cmu_cc" | grep -q '^006_' && fail "a held-out cmu_cc subject is in train"
ls "$work/poses/train/cmu_poses" | grep -q '^139_' && fail "a held-out cmu_poses subject is in train"
[ "$failures" = 0 ] && echo "pose_split: all checks passed"
