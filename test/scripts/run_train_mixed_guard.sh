#!/usr/bin/env bash
# scripts/train_mixed_models.sh, evaluate_moved.sh and real_frame_overlays.sh write only what is theirs.
# train_mixed_models.sh never writes over models already in its output folder (unless
# AGEX_TRAIN_FORCE=1) and refuses a bad AGEX_TRAIN_SCALE, AGEX_TRAIN_HOLDOUT,
# AGEX_TRAIN_BACKGROUND_RATIO, AGEX_TRAIN_DETECTORS, AGEX_TRAIN_WORKING_SPACING or AGEX_TRAIN_CLOTHES before any work, as train_bundled_models.sh
# an unknown AGEX_BUNDLED_RECIPE;
# evaluate_bonn.sh refuses an unknown AGEX_EVAL_RECIPE before making its folder, and a fold
# folder of the other recipe. Skips (77) without
# ../shared's data (the script checks it first).
# Usage: run_train_mixed_guard.sh SOURCE_DIR WORK_DIR
set -u
src=$1 work=$2
shared="$src/../shared/data"
for need in bonn mocap/cmu_cc mocap/cmu_poses makehuman/targets kinect/skeltrack; do
  [ -d "$shared/$need" ] || { echo "SKIP: $shared/$need is missing"; exit 77; }
done
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
rm -rf "$work" && mkdir -p "$work/out" || exit 1
echo "someone's model" > "$work/out/agex_bonn_sw.yml"
cp "$work/out/agex_bonn_sw.yml" "$work/orig"
bash "$src/scripts/train_mixed_models.sh" "$work/out" "$work/no_build" "$work/w" 2> "$work/err" && fail "it ran over an existing model"
cmp -s "$work/out/agex_bonn_sw.yml" "$work/orig" || fail "the existing model changed"
grep -q "exists" "$work/err" || fail "the refusal does not say why: $(cat "$work/err")"
[ -e "$work/w" ] && fail "it started work before refusing"
AGEX_TRAIN_SCALE=7 bash "$src/scripts/train_mixed_models.sh" "$work/new" "$work/no_build" "$work/w2" 2> "$work/err2" \
  && fail "AGEX_TRAIN_SCALE=7 was accepted"
grep -q "AGEX_TRAIN_SCALE" "$work/err2" || fail "the scale refusal does not name it: $(cat "$work/err2")"
AGEX_TRAIN_HOLDOUT=9 bash "$src/scripts/train_mixed_models.sh" "$work/new" "$work/no_build" "$work/w3" 2> "$work/err4" \
  && fail "AGEX_TRAIN_HOLDOUT=9 (no such Bonn sequence) was accepted"
grep -q "AGEX_TRAIN_HOLDOUT" "$work/err4" || fail "the hold-out refusal does not name it: $(cat "$work/err4")"
[ -e "$work/w3" ] && fail "it started work before refusing the hold-out"
AGEX_TRAIN_BACKGROUND_RATIO=-1 bash "$src/scripts/train_mixed_models.sh" "$work/new" "$work/no_build" "$work/w6" \
  2> "$work/err7" && fail "AGEX_TRAIN_BACKGROUND_RATIO=-1 was accepted"
grep -q "AGEX_TRAIN_BACKGROUND_RATIO" "$work/err7" || fail "the ratio refusal does not name it: $(cat "$work/err7")"
AGEX_TRAIN_CLOTHES=yes bash "$src/scripts/train_mixed_models.sh" "$work/new" "$work/no_build" "$work/w12" \
  2> "$work/err14" && fail "AGEX_TRAIN_CLOTHES=yes was accepted"
grep -q "AGEX_TRAIN_CLOTHES" "$work/err14" || fail "the clothes refusal does not name it: $(cat "$work/err14")"
[ -e "$work/w12" ] && fail "it started work before refusing AGEX_TRAIN_CLOTHES"
AGEX_TRAIN_DETECTORS="fused forest" bash "$src/scripts/train_mixed_models.sh" "$work/new" "$work/no_build" "$work/w7" \
  2> "$work/err8" && fail "AGEX_TRAIN_DETECTORS with an unknown detector was accepted"
grep -q "AGEX_TRAIN_DETECTORS" "$work/err8" || fail "the detector refusal does not name it: $(cat "$work/err8")"
AGEX_TRAIN_DETECTORS="fused fused" bash "$src/scripts/train_mixed_models.sh" "$work/new" "$work/no_build" "$work/w9" \
  2> "$work/err11" && fail "AGEX_TRAIN_DETECTORS naming a detector twice was accepted"
grep -q "names fused twice" "$work/err11" || fail "the repeated-detector refusal does not say why: $(cat "$work/err11")"
AGEX_TRAIN_BACKGROUND_RATIO="4_0" bash "$src/scripts/train_mixed_models.sh" "$work/new" "$work/no_build" "$work/w10" \
  2> /dev/null && fail "AGEX_TRAIN_BACKGROUND_RATIO=4_0 was accepted"
for spacing in 0.06 -0.01 1e-2 abc; do
  AGEX_TRAIN_WORKING_SPACING=$spacing bash "$src/scripts/train_mixed_models.sh" "$work/new" "$work/no_build" "$work/w11" \
    2> "$work/err12" && fail "AGEX_TRAIN_WORKING_SPACING=$spacing was accepted"
  grep -q "AGEX_TRAIN_WORKING_SPACING" "$work/err12" || fail "the spacing refusal does not name it: $(cat "$work/err12")"
done
[ -e "$work/w6" ] || [ -e "$work/w7" ] || [ -e "$work/w9" ] || [ -e "$work/w10" ] || [ -e "$work/w11" ] &&
  fail "it started work before refusing the ratio, the detectors or the spacing"
AGEX_BUNDLED_RECIPE=forest bash "$src/scripts/train_bundled_models.sh" "$work/no_build" "$work/w8" 2> "$work/err9" \
  && fail "train_bundled_models took an unknown recipe"
grep -q "AGEX_BUNDLED_RECIPE" "$work/err9" || fail "the bundled recipe refusal does not name it: $(cat "$work/err9")"
[ -e "$work/w8" ] && fail "train_bundled_models started work before refusing the recipe"
AGEX_EVAL_RECIPE=forest bash "$src/scripts/evaluate_bonn.sh" "$work/fold" 7,8 "$work/no_build" 2> "$work/err5" \
  && fail "evaluate_bonn took an unknown recipe"
grep -q "AGEX_EVAL_RECIPE" "$work/err5" || fail "the recipe refusal does not name it: $(cat "$work/err5")"
[ -e "$work/fold" ] && fail "evaluate_bonn made its folder before refusing the recipe"
mkdir -p "$work/bonnfold" && echo "a Bonn-recipe forest" > "$work/bonnfold/forest.agexforest"
AGEX_EVAL_RECIPE=mixed bash "$src/scripts/evaluate_bonn.sh" "$work/bonnfold" 7,8 "$work/no_build" 2> "$work/err6" \
  && fail "evaluate_bonn resumed a Bonn-recipe fold with the mixed recipe"
[ "$(cat "$work/bonnfold/forest.agexforest")" = "a Bonn-recipe forest" ] || fail "the Bonn-recipe fold's forest changed"
grep -q "holds the bonn recipe" "$work/err6" || fail "the mixed-recipe refusal does not say why: $(cat "$work/err6")"
# scripts/evaluate_moved.sh writes only into a folder of its own.
mkdir -p "$work/mine" && echo "a result of mine" > "$work/mine/agex_bonn_kinect_3m.json"
cp "$work/mine/agex_bonn_kinect_3m.json" "$work/mine.orig"
bash "$src/scripts/evaluate_moved.sh" "$work/mine" 7,8 "$src/data/models/agex_bonn.yml" -- "$work/no_build" \
  2> "$work/err3" && fail "evaluate_moved wrote into a folder of other things"
cmp -s "$work/mine/agex_bonn_kinect_3m.json" "$work/mine.orig" || fail "evaluate_moved changed a file it did not write"
echo x > "$work/afile"
bash "$src/scripts/evaluate_moved.sh" "$work/afile" 7,8 "$src/data/models/agex_bonn.yml" -- "$work/no_build" \
  2> /dev/null && fail "evaluate_moved took a file for its folder"
[ "$(cat "$work/afile")" = x ] || fail "evaluate_moved changed a file given as its folder"
# scripts/real_frame_overlays.sh writes only into a folder of its own.
mkdir -p "$work/photos" && echo "a picture of mine" > "$work/photos/five_people.png"
bash "$src/scripts/real_frame_overlays.sh" "$work/photos" "$src/data/models/agex_bonn.yml" "$work/no_build" \
  2> "$work/err10" && fail "real_frame_overlays wrote into a folder of other things"
[ "$(cat "$work/photos/five_people.png")" = "a picture of mine" ] || fail "real_frame_overlays changed a file it did not write"
grep -q "not an earlier real_frame_overlays folder" "$work/err10" || fail "the overlay refusal does not say why: $(cat "$work/err10")"
[ "$failures" = 0 ] && echo "train_mixed_models and evaluate_moved guards: all checks passed"
