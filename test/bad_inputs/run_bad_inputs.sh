#!/usr/bin/env bash
# ctest agex_bad_inputs: every app against the bad inputs of doc/bad_inputs.md. Each case
# checks the exit code, that the message names the problem, and that no input (and no
# earlier output) changed. Prints the table of doc/bad_inputs.md as it goes.
#   run_bad_inputs.sh BIN_DIR SOURCE_DIR WORK_DIR
set -u
BIN=$1 SRC=$2 WORK=$3
rm -rf "$WORK"
mkdir -p "$WORK/in" "$WORK/out"
cd "$WORK" || exit 2
failures=0

# Inputs: the fixtures, the bundled frame and model, cut and edited copies of them.
cp "$SRC"/test/bad_inputs/inputs/* in/
cp "$SRC/data/frames/bonn_1_002.png" in/frame.png
cp "$SRC/data/models/agex_bonn.yml" in/model.yml
head -c 20000 in/frame.png > in/truncated.png
: > in/empty.png
head -c 1000 /dev/zero > in/wrong_size.u16
head -c 100000 in/model.yml > in/truncated_model.yml
sed 's/^format_version: 1$/format_version: 2/' in/model.yml > in/version2_model.yml
head -c $((176 * 144 * 2)) /dev/zero | tr '\0' '\7' > in/wall_176x144.u16
"$BIN/agex_convert" u16 --input in/wall_176x144.u16 --output in/dataset --width 176 --height 144 >/dev/null 2>&1
head -c 300 in/dataset/frames/wall_176x144.pcd > in/truncated_compressed.pcd
cp "$SRC/test/fuzz/regressions/frame_pcd/repeated_fields_line_overflows_point.pcd" in/fields_overflow.pcd
for variant in truncated_json version2 truncated_labels wrong_frame_size; do cp -r in/dataset "in/ds_$variant"; done
head -c 200 in/dataset/dataset.json > in/ds_truncated_json/dataset.json
sed -i 's/"version": 1/"version": 2/' in/ds_version2/dataset.json
printf '%s\n%s' "$(head -1 in/dataset/labels.csv)" "wall_176x144,head,0,0.1,0.2" > in/ds_truncated_labels/labels.csv
cp in/nan_and_inf_depths_48x64.pcd in/ds_wrong_frame_size/frames/wall_176x144.pcd
(cd in && find . -type f -print0 | sort -z | xargs -0 sha256sum) > inputs.sha256

echo "| case | command | exit | what it gets |"
echo "| --- | --- | --- | --- |"

# check CASE EXPECTED_EXIT 'regex the output must match' command...
check () {
  local what=$1 want_exit=$2 want=$3
  shift 3
  local output status
  output=$("$@" 2>&1)
  status=$?
  local problems=""
  [ "$status" = "$want_exit" ] || problems+=" exit $status, expected $want_exit;"
  if [ -n "$want" ]; then
    printf '%s' "$output" | grep -Eq -- "$want" || problems+=" output does not match '$want';"
  fi
  (cd in && sha256sum --quiet -c ../inputs.sha256 >/dev/null 2>&1) || problems+=" an input changed;"
  local shown
  shown=$(printf '%s\n' "$output" | grep -E -- "${want:-.}" | head -1 | sed "s|$WORK/||g; s/|/\\\\|/g" | cut -c1-160)
  local command="${*/#$BIN\//}"
  command=${command//$WORK\//}
  echo "| $what | \`$command\` | $status | $shown |"
  if [ -n "$problems" ]; then
    echo "FAILED: $what:$problems" >&2
    printf '%s\n' "$output" | tail -5 >&2
    failures=$((failures + 1))
  fi
}

# check_kept CASE FILE CONTENT: an earlier output survives the failed run before it.
check_kept () {
  if [ "$(cat "$2" 2>/dev/null)" != "$3" ]; then
    echo "FAILED: $1: $2 was changed or removed" >&2
    failures=$((failures + 1))
  fi
}

D=$BIN/agex_detect K=$BIN/agex_keypoints E=$BIN/agex_eval C=$BIN/agex_convert T=$BIN/agex_train
# Frames.
check "truncated PNG" 1 "truncated.png: cannot decode PNG" $D in/truncated.png --json out/a.json
check "empty file" 1 "empty.png: cannot decode PNG" $K in/empty.png --json out/a.json
check "truncated binary_compressed PCD" 1 "truncated_compressed.pcd: PCD data" $D in/truncated_compressed.pcd --json out/a.json
check "PCD fields that do not fit the point" 1 "fields_overflow.pcd: .*(does not fit|4-byte float|damaged SIZE|more than one)" $K in/fields_overflow.pcd --json out/a.json
check ".u16 of the wrong size" 1 "wrong_size.u16: has 1000 bytes, expected 614400" $D in/wrong_size.u16 --json out/a.json
check "PNG claiming 100000x100000 pixels" 1 "claims a 100000x100000 frame" $D in/claims_100000x100000.png --json out/a.json
check ".u16 said to be 100000x100000" 1 "claims a 100000x100000 frame" $K in/wrong_size.u16 --width 100000 --height 100000 --json out/a.json
check "unorganized cloud (organized-only stages)" 1 "unorganized_3072x1.pcd: PCD cloud is not organized" $D in/unorganized_3072x1.pcd --json out/a.json
check "NaN, +inf and -inf depths" 0 "" $D in/nan_and_inf_depths_48x64.pcd --json out/nan_inf.json
grep -q '"detections"' out/nan_inf.json || { echo "FAILED: NaN/inf frame gave no JSON" >&2; failures=$((failures + 1)); }
check "all-invalid frame (PNG of zeros)" 0 "" $D in/all_invalid_640x480.png --json out/empty.json
grep -q '"detections":\[\]' <(tr -d ' \n' < out/empty.json) || { echo "FAILED: all-invalid frame: detections not empty" >&2; failures=$((failures + 1)); }
check "all-NaN PCD" 0 "" $K in/all_nan_48x64.pcd --json out/all_nan.json
grep -q '"interest_points":\[\]' <(tr -d ' \n' < out/all_nan.json) || { echo "FAILED: all-NaN frame: points not empty" >&2; failures=$((failures + 1)); }
check "1-pixel meshes only (isolated pixels)" 0 "" $K in/one_pixel_specks_640x480.png --min-mesh-size 1 --json out/specks.json
check "missing frame" 1 "nope.png: no such file" $D in/nope.png --json out/a.json
# Models.
check "model of another format version" 1 "version2_model.yml: model format version 2 is not supported" $D in/frame.png --model in/version2_model.yml --json out/a.json
check "truncated model" 1 "truncated_model.yml: damaged model file" $D in/frame.png --model in/truncated_model.yml --json out/a.json
check "a PNG given as the model" 1 "frame.png: not an agex model" $D in/frame.png --model in/frame.png --json out/a.json
# Datasets.
check "truncated dataset.json" 1 "ds_truncated_json/dataset.json: not valid JSON" $E coverage --dataset in/ds_truncated_json --json out/a.json
check "dataset of another format version" 1 "version 2 is not supported" $E coverage --dataset in/ds_version2 --json out/a.json
check "labels.csv cut in the middle of a line" 1 "labels.csv:2: expected 15 comma-separated fields" $E coverage --dataset in/ds_truncated_labels --json out/a.json
check "dataset frame of the wrong size" 1 "wall_176x144.pcd: is 48x64, the dataset says 176x144" $E coverage --dataset in/ds_wrong_frame_size --json out/a.json
# Training and synthesis.
printf 'HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 6 Xposition Yposition\n' > in/truncated.bvh
(cd in && find . -type f -print0 | sort -z | xargs -0 sha256sum) > inputs.sha256
S=$BIN/agex_synth
check "truncated BVH motion" 1 "truncated.bvh:5: " $S --motion in/truncated.bvh --frames 3 --sensor sr4000 --output out/synth
check "missing BVH motion" 1 "nope.bvh: cannot open BVH file" $S --motion in/nope.bvh --frames 3 --output out/synth
check "unknown sensor" 1 "unknown --sensor .nosuch." $S --motion in/truncated.bvh --frames 3 --sensor nosuch --output out/synth
check "train on a dataset without labels" 1 "training on 0 patches from 0 frames" $T --dataset in/dataset --out out/model.yml
check "train on a damaged labels.csv" 1 "labels.csv:2: expected 15" $T --dataset in/ds_truncated_labels --out out/model.yml
[ ! -e out/synth ] && [ ! -e out/model.yml ] || { echo "FAILED: a failed run left an output" >&2; failures=$((failures + 1)); }
# Outputs.
echo previous > out/kept.json
check "failing run, earlier output in the way" 1 "truncated.png" $D in/truncated.png --json out/kept.json
check_kept "failing run" out/kept.json previous
check "output directory that is a file" 1 "out/kept.json/x.json" $D in/frame.png --json out/kept.json/x.json
check_kept "output under a file" out/kept.json previous
check "output over an input" 1 "would overwrite an input" $D in/frame.png --overlay in/frame.png
check "convert onto an existing dataset" 1 "already exists" $C u16 --input in/wall_176x144.u16 --output in/dataset --width 176 --height 144
check "report under a file" 1 "out/kept.json/r.json" $E coverage --dataset in/dataset --json out/kept.json/r.json
check_kept "report under a file" out/kept.json previous

# Interrupted batch runs: killed part way, then run again.
mkdir -p in/batch
for i in $(seq -w 1 60); do cp in/wall_176x144.u16 "in/batch/f$i.u16"; done
(cd in && find . -type f -print0 | sort -z | xargs -0 sha256sum) > inputs.sha256
$D in/batch --width 176 --height 144 --json out/batch.jsonl >/dev/null 2>&1 &
pid=$!
for _ in $(seq 1 400); do [ -s out/batch.jsonl ] && [ "$(wc -l < out/batch.jsonl)" -ge 5 ] && break; sleep 0.05; done
kill -KILL $pid 2>/dev/null; wait $pid 2>/dev/null
printf '{"frame":"torn' >> out/batch.jsonl  # as if killed inside a write
before=$(grep -c . out/batch.jsonl)
check "agex_detect batch killed (SIGKILL) after $((before - 1)) frames, run again" 0 "already in" $D in/batch --width 176 --height 144 --json out/batch.jsonl
lines=$(wc -l < out/batch.jsonl) unique=$(grep -o '"frame":"[^"]*"' out/batch.jsonl | sort -u | wc -l)
[ "$lines" = 60 ] && [ "$unique" = 60 ] || { echo "FAILED: resumed batch has $lines lines, $unique frames (want 60)" >&2; failures=$((failures + 1)); }
# Full-size frames, so that the conversion is still running when it is killed.
mkdir -p in/batch_vga
head -c $((640 * 480 * 2)) /dev/zero | tr '\0' '\7' > in/batch_vga/f00.u16
for i in $(seq -w 1 39); do cp in/batch_vga/f00.u16 "in/batch_vga/f$i.u16"; done
(cd in && find . -type f -print0 | sort -z | xargs -0 sha256sum) > inputs.sha256
$C u16 --input in/batch_vga --output out/converted >/dev/null 2>&1 &
pid=$!
for _ in $(seq 1 1000); do ls out/.converted.partial-*/frames/*.pcd >/dev/null 2>&1 && break; sleep 0.01; done
kill -KILL $pid 2>/dev/null; wait $pid 2>/dev/null
[ ! -e out/converted ] || { echo "FAILED: a killed conversion left a dataset" >&2; failures=$((failures + 1)); }
[ "$(ls -a out | grep -c partial)" = 1 ] || { echo "FAILED: the killed conversion left no staging directory (not killed in time?)" >&2; failures=$((failures + 1)); }
check "agex_convert killed (SIGKILL) while writing, run again" 0 "40 frames" $C u16 --input in/batch_vga --output out/converted
left=$(ls -a out | grep -c partial)
[ "$left" = 0 ] || { echo "FAILED: $left staging directories left after the rerun" >&2; failures=$((failures + 1)); }

# Outputs that would land on what a run reads: models, a dataset's files, the frames.
head -c 200 /dev/zero | tr '\0' '\7' > in/one_row_100x1.u16
mkdir -p in/no_frames
echo "my notes" > in/notes.txt
(cd in && find . -type f -print0 | sort -z | xargs -0 sha256sum) > inputs.sha256
check "JSON over the model" 1 "model.yml: output would overwrite an input" $D in/frame.png --model in/model.yml --json in/model.yml
check "JSON lines over a dataset's labels" 1 "labels.csv: output would overwrite an input" $D in/dataset --json in/dataset/labels.csv
check "report over a dataset's labels" 1 "labels.csv: output would overwrite an input" $E detect --dataset in/dataset --json in/dataset/labels.csv
check "plot over a dataset frame" 1 "wall_176x144.pcd: output would overwrite an input" $E coverage --dataset in/dataset --plot in/dataset/frames/wall_176x144.pcd
check "model over a dataset's labels" 1 "labels.csv: output would overwrite an input" $T --dataset in/dataset --out in/dataset/labels.csv
check "benchmark over a dataset frame" 1 "wall_176x144.pcd: output would overwrite an input" $BIN/agex_bench --dataset in/dataset --json in/dataset/frames/wall_176x144.pcd
check "batch JSON lines onto a file that is not a batch result" 1 "notes.txt: line 1 is not a frame result" $D in/batch --width 176 --height 144 --json in/notes.txt
check "a directory without frames" 1 "no_frames: no frames" $D in/no_frames --json out/none.jsonl
check "a frame one row high" 1 "one_row_100x1.u16: a 100x1 image; a depth frame needs at least 2 rows" $K in/one_row_100x1.u16 --width 100 --height 1
check "a NaN focal length" 1 "--fy must be a positive number" $K in/frame.png --fy nan
check "a median window of 100000 pixels" 1 "--median-window is 100000, outside \\[0, 31\\]" $K in/frame.png --median-window 100000
# Reruns find their frames however the input is spelled; more jobs than frames is fine.
check "agex_detect rerun as ./in/batch/" 0 "60 frames already in" $D ./in/batch/ --width 176 --height 144 --json out/batch.jsonl
[ "$(wc -l < out/batch.jsonl)" = 60 ] || { echo "FAILED: the respelled rerun added lines" >&2; failures=$((failures + 1)); }
head -c -1 out/batch.jsonl > out/no_newline.jsonl  # the last line lost its newline
sed -i '$d' out/no_newline.jsonl && head -c -1 out/no_newline.jsonl > out/cut.jsonl
check "agex_detect rerun onto a file whose last line has no newline" 0 "59 frames already in" $D in/batch --width 176 --height 144 --json out/cut.jsonl
[ "$(grep -c '^{.*}$' out/cut.jsonl)" = 60 ] || { echo "FAILED: the appended line was glued to the last one" >&2; failures=$((failures + 1)); }
check "agex_detect --jobs 100000" 0 "" $D in/batch --width 176 --height 144 --json out/jobs.jsonl --jobs 100000
[ "$(wc -l < out/jobs.jsonl)" = 60 ] || { echo "FAILED: --jobs 100000 did not give 60 lines" >&2; failures=$((failures + 1)); }

if [ "$failures" -gt 0 ]; then
  echo "$failures bad-input case(s) failed" >&2
  exit 1
fi
echo "all bad-input cases behave as documented" >&2
