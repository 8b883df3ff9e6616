#!/usr/bin/env bash
# The table of doc/results.md, "The fused detector against every baseline", for one fold:
# trains the four depth models of scripts/train_bundled_models.sh (AGEX_BUNDLED_RECIPE=bonn's
# recipe; AGEX_EVAL_RECIPE=mixed below for today's) on the Bonn sequences that are not TEST, then scores on TEST's keyframes, portrait and full view:
# AGEX only, the sliding-window baseline, PCL's forest alone, our forest alone, fused (with the
# fold's sliding window blended in, as the bundled model has it), and the
# fused model with agex 0.1's crop box in place of person isolation (box: what isolation costs
# on Bonn, whose people all stand in that box).
# Writes OUT/ev_<detector>_<view>.json (agex_eval detect reports) and prints the fold's table
# (scripts/bonn_table.py). Folds already trained or scored in OUT are kept, so an interrupted
# run resumes. About 20 minutes per fold on 2 cores. The converted Bonn datasets (both views)
# go to OUT/../bonn-datasets, shared by the folds beside OUT.
# AGEX_EVAL_RECIPE=mixed trains the fold's models with scripts/train_mixed_models.sh instead
# (synthetic people and re-projected frames, TEST's sequences and their moved copies left out;
# its rendered datasets go to OUT/../mixed-work, shared by the folds): about 50 minutes a fold
# for the fused detector once the datasets are rendered (more with the baselines).
#   scripts/evaluate_bonn.sh OUT TEST [BUILD_DIR]      e.g. OUT=/tmp/split TEST=7,8
# Leave-one-sequence-out: for s in 1 2 3 4 5 6 7 8; do scripts/evaluate_bonn.sh /tmp/loso/$s $s; done
#                         scripts/bonn_table.py /tmp/loso/[0-9]*
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OUT=$1 TEST=$2
BIN="${3:-$ROOT/build}/bin"
BONN="$ROOT/../shared/data/bonn"
PCL_FORESTS="$ROOT/../shared/data/pcl_people"
[ -d "$BONN" ] || { echo "evaluate_bonn: $BONN is missing (the Bonn frames of ../shared)" >&2; exit 1; }
[ -d "$PCL_FORESTS" ] || { echo "evaluate_bonn: $PCL_FORESTS is missing (PCL's forests of ../shared)" >&2; exit 1; }
[[ $TEST =~ ^[1-8](,[1-8])*$ ]] || { echo "evaluate_bonn: TEST must be Bonn sequences such as 7,8, not '$TEST'" >&2; exit 1; }
RECIPE_NAME=${AGEX_EVAL_RECIPE:-bonn}
[[ $RECIPE_NAME = bonn || $RECIPE_NAME = mixed ]] ||
  { echo "evaluate_bonn: AGEX_EVAL_RECIPE must be bonn or mixed, not '$RECIPE_NAME'" >&2; exit 1; }
# A fold folder holds one recipe's models: resuming it with the other would mix or overwrite
# them (folders of before this record hold the Bonn recipe).
if [ -d "$OUT" ] && [ -n "$(ls -A "$OUT")" ]; then
  made_with=$(cat "$OUT/.recipe" 2> /dev/null || echo bonn)
  [ "$made_with" = "$RECIPE_NAME" ] ||
    { echo "evaluate_bonn: $OUT holds the $made_with recipe's fold, not $RECIPE_NAME's: use another folder" >&2; exit 1; }
fi
mkdir -p "$OUT"
echo "$RECIPE_NAME" > "$OUT/.recipe"
DATA="$OUT/../bonn-datasets"
for view in portrait full; do
  [ -f "$DATA/bonn-$view/dataset.json" ] || "$BIN/agex_convert" bonn --input "$BONN" --output "$DATA/bonn-$view" --view "$view"
done
TRAIN=$(seq 1 8 | grep -vxF -f <(echo "$TEST" | tr ',' '\n') | paste -sd,)
echo "evaluate_bonn: train on $TRAIN, test on the keyframes of $TEST"
both () { echo --dataset "$DATA/bonn-full@$1" --dataset "$DATA/bonn-portrait@$1"; }
FOREST_FLAGS=(--hand-reach 0.12 --threads 2)
RECIPE=(--k 16 --weak-count 200 --fragments 100 --random-negatives 3)
# Writes to a temporary name first, so that an interrupted step is redone, not kept half-made.
made () { [ -s "$1" ]; }

case "$RECIPE_NAME" in
  bonn) ;;
  mixed)
    if ! made "$OUT/fused.yml"; then
      AGEX_TRAIN_HOLDOUT=$TEST AGEX_TRAIN_FORCE=1 bash "$ROOT/scripts/train_mixed_models.sh" "$OUT/mixed" "${BIN%/bin}" \
        "$OUT/../mixed-work"
      # The fused model names its forest beside itself (agex_bonn_forest.agexforest).
      cp "$OUT/mixed/agex_bonn_forest.agexforest" "$OUT/agex_bonn_forest.agexforest"
      cp "$OUT/mixed/agex_bonn_forest.agexforest" "$OUT/forest.agexforest"
      cp "$OUT/mixed/agex_bonn_agex.yml" "$OUT/agex.yml"
      cp "$OUT/mixed/agex_bonn_sw.yml" "$OUT/sw.yml"
      cp "$OUT/mixed/agex_bonn_sw.yml" "$OUT/agex_bonn_sw.yml"  # the window model it names
      cp "$OUT/mixed/agex_bonn.yml" "$OUT/fused.tmp.yml" && mv "$OUT/fused.tmp.yml" "$OUT/fused.yml"
    fi ;;
esac
made "$OUT/forest.agexforest" || { "$BIN/agex_train_forest" $(both "$TRAIN") "${FOREST_FLAGS[@]}" --out "$OUT/forest.tmp.agexforest" \
  && mv "$OUT/forest.tmp.agexforest" "$OUT/forest.agexforest"; }
# Cross-fitting as for the bundled model: the training sequences in groups of two, each
# group's frames labelled by a forest trained without it.
fold_args=()
made "$OUT/fused.yml" && groups="" || groups=$(echo "$TRAIN" | tr ',' '\n' | paste -d, - - | sed 's/,$//')
for group in $groups; do
  rest=$(echo "$TRAIN" | tr ',' '\n' | grep -vxF -f <(echo "$group" | tr ',' '\n') | paste -sd,)
  f="$OUT/forest_without_${group//,/}.agexforest"
  made "$f" || { "$BIN/agex_train_forest" $(both "$rest") "${FOREST_FLAGS[@]}" --out "$f.tmp" && mv "$f.tmp" "$f"; }
  for view in full portrait; do
    fold_args+=(--dataset "$DATA/bonn-$view@$group" --dataset-forest "$DATA/bonn-$view@$group=$f")
  done
done
made "$OUT/fused.yml" || { "$BIN/agex_train" --fused --forest "$OUT/forest.agexforest" "${fold_args[@]}" "${RECIPE[@]}" \
  --out "$OUT/fused.tmp.yml" && mv "$OUT/fused.tmp.yml" "$OUT/fused.yml"; }
made "$OUT/agex.yml" || { "$BIN/agex_train" $(both "$TRAIN") "${RECIPE[@]}" --out "$OUT/agex.tmp.yml" \
  && mv "$OUT/agex.tmp.yml" "$OUT/agex.yml"; }
made "$OUT/box.yml" || { python3 "$ROOT/scripts/set_model_pipeline.py" "$OUT/fused.yml" "$OUT/box.tmp.yml" \
  isolate_people=false use_crop_box=true && mv "$OUT/box.tmp.yml" "$OUT/box.yml"; }
made "$OUT/sw.yml" || { "$BIN/agex_train" --sliding-window $(both "$TRAIN") --weak-count 300 --fragments 150 \
  --out "$OUT/sw.tmp.yml" && mv "$OUT/sw.tmp.yml" "$OUT/sw.yml"; }

for view in portrait full; do
  set_="$DATA/bonn-$view@$TEST"
  score () {
    local name=$1; shift
    made "$OUT/ev_${name}_$view.json" || "$BIN/agex_eval" detect --dataset "$set_" --keyframes "$@" \
      --json "$OUT/ev_${name}_$view.json" > "$OUT/ev_${name}_$view.log"
  }
  score agex --model "$OUT/agex.yml"
  score sw --model "$OUT/sw.yml"
  score pcl_forest --model "$OUT/agex.yml" --detector-mode forest --forest "$PCL_FORESTS"
  score our_forest --model "$OUT/agex.yml" --detector-mode forest --forest "$OUT/forest.agexforest"
  # The fused detector with the fold's own sliding window blended in, as the bundled one has it.
  score fused --model "$OUT/fused.yml" --window-model "$OUT/sw.yml"
  score box --model "$OUT/box.yml" --window-model "$OUT/sw.yml"
done
python3 "$ROOT/scripts/bonn_table.py" "$OUT"
