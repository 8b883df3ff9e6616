#!/usr/bin/env bash
# Trains a forest and three detectors (fused, AGEX-only, sliding window) on the mix issue #33
# asks for (doc/results.md, "Every distance, every camera"); the bundled models' recipe
# (scripts/train_bundled_models.sh). Each model sees the same mix of
#   - synthetic people (MakeHuman bodies of sampled shapes, the training part of the pose split
#     of scripts/pose_split.sh, whole scenes with 1-3 people at 0.8-6 m, with and without floor
#     and background, cut by the borders, close-range upper bodies) through every sensor model
#     and resolution, and
#   - the real Bonn frames of sequences 1-8 as recorded (both views) and re-projected
#     (agex_reproject): moved to 0.8-5 m, sideways, up and down, the camera tilted, rendered
#     by the Kinect v1 at 640x480 and 320x240, the Kinect v2-like camera and the Bonn view.
# The fused detector's classifier is trained on forest features cross-fitted over four groups
# (Bonn sequence pairs with their re-projected copies, and a quarter of the synthetic sets
# each): every group's frames are labelled by a forest trained without them.
# Usage: scripts/train_mixed_models.sh OUT_DIR [BUILD_DIR] [WORK_DIR]
# Writes OUT_DIR/agex_bonn.yml (fused, naming agex_bonn_forest.agexforest beside it, and
# agex_bonn_sw.yml when the sliding window is trained too or already there),
# agex_bonn_agex.yml and agex_bonn_sw.yml. Stages are checkpoints: a rerun with the same
# WORK_DIR skips the datasets and forests already there. AGEX_TRAIN_SCALE (0.05-1, default 1)
# renders that fraction of the synthetic frames and moves only the keyframes: a quick trial
# (0.1: about 20 minutes on 2 cores). At full scale on 2 cores: the datasets 14 minutes, the
# forest 9, the four cross-fitting forests 18, then the detectors side by side: the fused
# classifier 31 minutes (139,000 patches with the background at 4 per positive), the sliding
# window 44, the AGEX-only model 43 (144,000 patches; measured beside two other training runs
# on the 2 cores). AGEX_TRAIN_HOLDOUT (Bonn sequences, e.g. 7,8) leaves
# those sequences and their re-projected copies out of every model, for a held-out evaluation;
# the rendered datasets are shared with other runs in the same WORK_DIR. Existing models in
# OUT_DIR are kept unless AGEX_TRAIN_FORCE=1. AGEX_TRAIN_BACKGROUND_RATIO (default 4, 0 keeps
# all) thins the background examples of the fused and AGEX-only detectors to that many per
# positive (agex_train --background-ratio); AGEX_TRAIN_DETECTORS (default "fused agex sw")
# picks the detectors trained; AGEX_TRAIN_WORKING_SPACING (metres, default 0: every pixel)
# trains the detectors at that working density (agex_train --working-spacing, doc/pipeline.md).
# AGEX_TRAIN_CLOTHES=1 dresses the synthetic people (agex_synth --clothes: sleeves, trousers,
# shoes and hair of drawn thickness; default 0, the bare meshes the bundled models saw).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
MODELS=${1:?usage: train_mixed_models.sh OUT_DIR [BUILD_DIR] [WORK_DIR]}
BIN="${2:-$ROOT/build}/bin"
WORK="${3:-$(mktemp -d)}"
SHARED="$ROOT/../shared/data"
# AGEX_TRAIN_SCALE (0.05-1, default 1): a fraction of the synthetic frames, for a quick trial.
SCALE="${AGEX_TRAIN_SCALE:-1}"
python3 -c "import sys; s = float(sys.argv[1]); sys.exit(0 if 0.05 <= s <= 1 else 1)" "$SCALE" 2> /dev/null ||
  { echo "train_mixed_models: AGEX_TRAIN_SCALE must be 0.05-1, not '$SCALE'" >&2; exit 1; }
HOLDOUT="${AGEX_TRAIN_HOLDOUT:-}"
[[ -z "$HOLDOUT" || "$HOLDOUT" =~ ^[1-8](,[1-8])*$ ]] ||
  { echo "train_mixed_models: AGEX_TRAIN_HOLDOUT must list Bonn sequences 1-8 (e.g. 7,8), not '$HOLDOUT'" >&2; exit 1; }
CLOTHES="${AGEX_TRAIN_CLOTHES:-0}"
[[ "$CLOTHES" =~ ^[01]$ ]] || { echo "train_mixed_models: AGEX_TRAIN_CLOTHES must be 0 or 1, not '$CLOTHES'" >&2; exit 1; }
# Dressed synthetic sets, and forests trained on them, have their own names in WORK_DIR, as
# forests trained without the held-out sequences do: a rerun never takes one for the other.
DRESS=""
[ "$CLOTHES" = 1 ] && DRESS=_clothes
TAG=${HOLDOUT:+_without_${HOLDOUT//,/}}$DRESS
RATIO="${AGEX_TRAIN_BACKGROUND_RATIO:-4}"
[[ "$RATIO" =~ ^[0-9]+(\.[0-9]+)?$ ]] &&
  python3 -c "import sys; sys.exit(0 if float(sys.argv[1]) <= 1000 else 1)" "$RATIO" 2> /dev/null ||
  { echo "train_mixed_models: AGEX_TRAIN_BACKGROUND_RATIO must be a number 0-1000, not '$RATIO'" >&2; exit 1; }
SPACING="${AGEX_TRAIN_WORKING_SPACING:-0}"
[[ "$SPACING" =~ ^0(\.[0-9]+)?$ ]] &&
  python3 -c "import sys; sys.exit(0 if float(sys.argv[1]) <= 0.05 else 1)" "$SPACING" 2> /dev/null ||
  { echo "train_mixed_models: AGEX_TRAIN_WORKING_SPACING must be metres 0-0.05, not '$SPACING'" >&2; exit 1; }
read -ra DETECTOR_LIST <<< "${AGEX_TRAIN_DETECTORS:-fused agex sw}"
[ ${#DETECTOR_LIST[@]} -gt 0 ] || { echo "train_mixed_models: AGEX_TRAIN_DETECTORS is empty" >&2; exit 1; }
seen=" "
for d in "${DETECTOR_LIST[@]}"; do
  case "$d" in fused|agex|sw) ;; *)
    echo "train_mixed_models: AGEX_TRAIN_DETECTORS lists fused, agex and sw, not '$d'" >&2; exit 1 ;;
  esac
  [[ "$seen" == *" $d "* ]] && { echo "train_mixed_models: AGEX_TRAIN_DETECTORS names $d twice" >&2; exit 1; }
  seen="$seen$d "
done
frames () { python3 -c "import sys; print(max(20, round($1 * float(sys.argv[1]))))" "$SCALE"; }
for need in "$SHARED/bonn" "$SHARED/mocap/cmu_cc" "$SHARED/mocap/cmu_poses" "$SHARED/makehuman/targets"; do
  [ -d "$need" ] || { echo "train_mixed_models: $need is missing (see ../shared/README.md)" >&2; exit 1; }
done
if [ "${AGEX_TRAIN_FORCE:-0}" != 1 ]; then
  for f in agex_bonn.yml agex_bonn_forest.agexforest agex_bonn_agex.yml agex_bonn_sw.yml; do
    [ -e "$MODELS/$f" ] && { echo "train_mixed_models: $MODELS/$f exists (AGEX_TRAIN_FORCE=1 replaces it)" >&2; exit 1; }
  done
fi
mkdir -p "$WORK" "$MODELS"
stamp () { echo "train_mixed_models: $(date -u +%H:%M:%S) $*"; }
once () {  # once NAME COMMAND...: runs COMMAND unless NAME (a dataset or a model) exists
  local name=$1; shift
  [ -e "$WORK/$name/dataset.json" ] || [ -f "$WORK/$name" ] && return 0
  stamp "$name"
  "$@" > "$WORK/${name%.*}.log" 2>&1 || { echo "train_mixed_models: $name failed (log: $WORK/${name%.*}.log)" >&2; return 1; }
}

# 1. Real frames: both views as recorded, and re-projected.
for view in portrait full; do
  once "bonn-$view" "$BIN/agex_convert" bonn --input "$SHARED/bonn" --output "$WORK/bonn-$view" --view "$view"
done
MOVE=(--dataset "$WORK/bonn-full" --sideways 0.6 --vertical 0.3 --tilt-deg 10)
# A trial (AGEX_TRAIN_SCALE below 1) moves the keyframes only.
python3 -c "import sys; sys.exit(0 if float(sys.argv[1]) < 1 else 1)" "$SCALE" && MOVE+=(--keyframes-only)
( once moved-k640 "$BIN/agex_reproject" "${MOVE[@]}" --distance-range 0.8:5 --sensor kinect --seed 11 --output "$WORK/moved-k640"
  once moved-bonn "$BIN/agex_reproject" "${MOVE[@]}" --distance-range 1.2:4 --sensor bonn --seed 13 --output "$WORK/moved-bonn" ) &
first=$!
( once moved-k320 "$BIN/agex_reproject" "${MOVE[@]}" --distance-range 0.8:5 --sensor kinect --resolution 320x240 --seed 12 --output "$WORK/moved-k320"
  once moved-k2 "$BIN/agex_reproject" "${MOVE[@]}" --distance-range 0.8:5 --sensor kinect2 --seed 14 --output "$WORK/moved-k2" ) &
second=$!
wait "$first" && wait "$second"

# 2. Synthetic people from the training part of the pose split (held-out subjects never seen).
bash "$ROOT/scripts/pose_split.sh" "$WORK/poses" > /dev/null
M="$SHARED/mocap"
SHAPES=(--body-mesh "$SHARED/makehuman" --body-shapes --subjects 24)
[ "$CLOTHES" = 1 ] && SHAPES+=(--clothes)
BANK=(--pose-dir "$WORK/poses/train/cmu_cc" --pose-dir "$WORK/poses/train/cmu_poses" --procedural-poses 2000 --thin-poses 0.05)
FIVE=(--motion "$M/cmu_02_01.bvh" "$M/cmu_05_06.bvh" "$M/cmu_131_01.bvh" "$M/cmu_131_02.bvh" "$M/cmu_131_03.bvh")
synth () { local name=$1$DRESS; shift; once "$name" "$BIN/agex_synth" "${SHAPES[@]}" "$@" --output "$WORK/$name"; }
( synth bank_k640 "${BANK[@]}" --layout whole --people 3 --sensor kinect --frames $(frames 400) --seed 101
  synth bank_k2 "${BANK[@]}" --layout whole --people 3 --sensor kinect2 --frames $(frames 200) --seed 103
  synth five_k640 "${FIVE[@]}" --layout whole --people 3 --sensor kinect --kinect-window 9 --frames $(frames 200) --seed 105 ) &
first=$!
( synth bank_k320 "${BANK[@]}" --layout whole --people 3 --sensor kinect --resolution 320x240 --frames $(frames 400) --seed 102
  synth bank_bonn "${BANK[@]}" --sensor bonn --frames $(frames 300) --seed 104
  synth five_bonn "${FIVE[@]}" --sensor bonn --frames $(frames 200) --seed 106
  synth five_k320 "${FIVE[@]}" --layout whole --people 3 --sensor kinect --resolution 320x240 --kinect-window 9 \
    --frames $(frames 200) --seed 107 ) &
second=$!
wait "$first" && wait "$second"

# Four groups for cross-fitting: Bonn sequence pairs (as recorded and moved) and synthetic sets.
REAL=(bonn-full bonn-portrait moved-k640 moved-k320 moved-k2 moved-bonn)
GROUP_SEQS=()
for pair in 1,2 3,4 5,6 7,8; do  # each pair less the held-out sequences (may be empty)
  GROUP_SEQS+=("$(echo "$pair" | tr ',' '\n' | grep -vxF -f <(echo "${HOLDOUT:-0}" | tr ',' '\n') | paste -sd, || true)")
done
GROUP_SYNTH=("bank_k640$DRESS five_bonn$DRESS" "bank_k320$DRESS five_k640$DRESS" "bank_k2$DRESS five_k320$DRESS"
  "bank_bonn$DRESS")
group_args () {  # group_args G [FOREST]: the --dataset (and --dataset-forest) flags of group G
  local g=$1 forest=${2:-} d
  [ -n "${GROUP_SEQS[$g]}" ] && for d in "${REAL[@]}"; do
    echo --dataset "$WORK/$d@${GROUP_SEQS[$g]}"
    [ -n "$forest" ] && echo --dataset-forest "$WORK/$d@${GROUP_SEQS[$g]}=$forest"
  done
  for d in ${GROUP_SYNTH[$g]}; do
    echo --dataset "$WORK/$d"
    [ -n "$forest" ] && echo --dataset-forest "$WORK/$d=$forest"
  done
  return 0
}
all_args () { local g; for g in 0 1 2 3; do group_args "$g"; done; }

# 3. The forest on everything, and one without each group for cross-fitting.
FOREST_FLAGS=(--hand-reach 0.12 --threads 2)
# 500 pixels a frame: the mix has six times the frames of the Bonn-only recipe, so each tree
# still sees three times its pixels, in half the time of 1000.
once "forest$TAG.agexforest" "$BIN/agex_train_forest" $(all_args) "${FOREST_FLAGS[@]}" --pixels-per-frame 500 \
  --out "$WORK/forest$TAG.agexforest"
fold_args=()
for g in 0 1 2 3; do
  rest=()
  for h in 0 1 2 3; do [ "$h" = "$g" ] || rest+=($(group_args "$h")); done
  once "forest${TAG}_group_$g.agexforest" "$BIN/agex_train_forest" "${rest[@]}" "${FOREST_FLAGS[@]}" --trees 2 \
    --pixels-per-frame 500 --out "$WORK/forest${TAG}_group_$g.agexforest"
  fold_args+=($(group_args "$g" "$WORK/forest${TAG}_group_$g.agexforest"))
done

# 4. The detectors, written into OUT_DIR (the fused model names its forest relative to
# itself, so the forest goes there first).
# Only with the fused detector: a fused model already there keeps the forest it was trained on.
[[ "$seen" == *" fused "* ]] && cp "$WORK/forest$TAG.agexforest" "$MODELS/agex_bonn_forest.agexforest"
RECIPE=(--k 16 --weak-count 200 --fragments 100 --random-negatives 3 --working-spacing "$SPACING")
# The fused model names the sliding-window model beside it, trained now or before, whose
# confidences it blends into its candidates' (doc/results.md: every class gains on held-out data).
WINDOW=()
if [[ "$seen" == *" sw "* ]] || [ -f "$MODELS/agex_bonn_sw.yml" ]; then
  WINDOW=(--window-model "$MODELS/agex_bonn_sw.yml" --window-weight 0.3)
fi
# agex_train uses one core: the detectors train side by side.
stamp "detectors: ${DETECTOR_LIST[*]}"
jobs_started=()
for d in "${DETECTOR_LIST[@]}"; do
  case "$d" in
  fused) "$BIN/agex_train" --fused --forest "$MODELS/agex_bonn_forest.agexforest" "${fold_args[@]}" "${RECIPE[@]}" \
           "${WINDOW[@]}" --background-ratio "$RATIO" --out "$MODELS/agex_bonn.yml" > "$WORK/fused$TAG.log" 2>&1 & ;;
  agex) "$BIN/agex_train" $(all_args) "${RECIPE[@]}" --background-ratio "$RATIO" --out "$MODELS/agex_bonn_agex.yml" \
          > "$WORK/agex$TAG.log" 2>&1 & ;;
  sw) "$BIN/agex_train" --sliding-window $(all_args) --weak-count 300 --fragments 150 --working-spacing "$SPACING" \
        --out "$MODELS/agex_bonn_sw.yml" \
        > "$WORK/sw$TAG.log" 2>&1 & ;;
  esac
  jobs_started+=("$!:$d$TAG")
done
failed=0
for job in "${jobs_started[@]}"; do
  wait "${job%%:*}" || { echo "train_mixed_models: ${job#*:} failed (log: $WORK/${job#*:}.log)" >&2; failed=1; }
done
[ "$failed" = 0 ]
stamp done
ls -l "$MODELS"/agex_bonn*
