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
cp "$SRC/data/models/agex_bonn_forest.agexforest" in/  # the fused model's forest, named relative to it
cp "$SRC/data/models/agex_bonn_sw.yml" in/  # and its window model
cp "$SRC/data/models/agex_bonn_agex.yml" in/agex_model.yml
head -c 20000 in/frame.png > in/truncated.png
: > in/empty.png
head -c 1000 /dev/zero > in/wrong_size.u16
head -c 100000 in/model.yml > in/truncated_model.yml
sed 's/^format_version: [0-9]*$/format_version: 3/' in/model.yml > in/version3_model.yml
head -c $((176 * 144 * 2)) /dev/zero | tr '\0' '\7' > in/wall_176x144.u16
# A 176x144 .u16 camera: its size and intrinsics (depth images of 640x480 need none).
SR="--width 176 --height 144 --fx 250 --fy 250 --cx 87.5 --cy 71.5"
"$BIN/agex_convert" u16 --input in/wall_176x144.u16 --output in/dataset $SR >/dev/null 2>&1
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

# capped MEGABYTES SECONDS command...: runs the command with its memory and time bounded, so
# that an input which would blow up is refused within the bound (a run past it is killed and
# its case fails on the exit code). The memory cap is ulimit -v where the apps start under it;
# a sanitizer build reserves terabytes of address space, so there ASan's RSS limit stands in.
if (ulimit -v 4194304; "$BIN/agex_detect" --help) >/dev/null 2>&1; then memory_cap=ulimit; else memory_cap=asan; fi
capped () {
  local megabytes=$1 seconds=$2
  shift 2
  if [ "$memory_cap" = ulimit ]; then
    (ulimit -v $((megabytes * 1024)); exec timeout -s KILL "$seconds" "$@")
  else
    ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}hard_rss_limit_mb=$megabytes" timeout -s KILL "$((seconds * 4))" "$@"
  fi
}

# hash_inputs: records every input's checksum (call again after adding inputs).
hash_inputs () { (cd "$WORK/in" && find . -type f -print0 | sort -z | xargs -0 sha256sum) > "$WORK/inputs.sha256"; }

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
check "model of another format version" 1 "version3_model.yml: model format version 3 is not supported" $D in/frame.png --model in/version3_model.yml --json out/a.json
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
check "procedural poses out of range" 1 "--procedural-poses must be 0-100000, got -1" $S --procedural-poses -1 --frames 3 --output out/synth
check "pose thinning out of range" 1 "--thin-poses must be 0-1 metres" $S --procedural-poses 10 --thin-poses 2 --frames 3 --output out/synth
check "missing pose directory" 1 "nope: not a directory of BVH files" $S --pose-dir in/nope --frames 3 --output out/synth
check "train on a dataset without labels" 1 "no training examples: no labelled frame with a body" $T --dataset in/dataset --out out/model.yml
check "train on a damaged labels.csv" 1 "labels.csv:2: expected 15" $T --dataset in/ds_truncated_labels --out out/model.yml
[ ! -e out/synth ] && [ ! -e out/model.yml ] || { echo "FAILED: a failed run left an output" >&2; failures=$((failures + 1)); }
# Outputs.
$D in/frame.png --json out/kept.json >/dev/null 2>&1
previous=$(cat out/kept.json)
check "failing run, earlier output in the way" 1 "truncated.png" $D in/truncated.png --json out/kept.json
check_kept "failing run" out/kept.json "$previous"
check "output directory that is a file" 1 "out/kept.json/x.json" $D in/frame.png --json out/kept.json/x.json
check_kept "output under a file" out/kept.json "$previous"
check "output over an input" 1 "would overwrite an input" $D in/frame.png --overlay in/frame.png
check "convert onto an existing dataset" 1 "already exists" $C u16 --input in/wall_176x144.u16 --output in/dataset $SR
check "report under a file" 1 "out/kept.json/r.json" $E coverage --dataset in/dataset --json out/kept.json/r.json
check_kept "report under a file" out/kept.json "$previous"

# Interrupted batch runs: killed part way, then run again.
mkdir -p in/batch
for i in $(seq -w 1 60); do cp in/wall_176x144.u16 "in/batch/f$i.u16"; done
(cd in && find . -type f -print0 | sort -z | xargs -0 sha256sum) > inputs.sha256
$D in/batch $SR --json out/batch.jsonl >/dev/null 2>&1 &
pid=$!
for _ in $(seq 1 400); do [ -s out/batch.jsonl ] && [ "$(wc -l < out/batch.jsonl)" -ge 5 ] && break; sleep 0.05; done
kill -KILL $pid 2>/dev/null; wait $pid 2>/dev/null
printf '{"frame":"torn' >> out/batch.jsonl  # as if killed inside a write
before=$(grep -c . out/batch.jsonl)
check "agex_detect batch killed (SIGKILL) after $((before - 1)) frames, run again" 0 "already in" $D in/batch $SR --json out/batch.jsonl
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
check "report over a dataset's labels" 1 "labels.csv: output would land inside the input dataset" $E detect --dataset in/dataset --json in/dataset/labels.csv
check "plot over a dataset frame" 1 "wall_176x144.pcd: output would land inside the input dataset" $E coverage --dataset in/dataset --plot in/dataset/frames/wall_176x144.pcd
check "model over a dataset's labels" 1 "labels.csv: output would land inside the input dataset" $T --dataset in/dataset --out in/dataset/labels.csv
check "benchmark over a dataset frame" 1 "wall_176x144.pcd: output would overwrite an input" $BIN/agex_bench --dataset in/dataset --json in/dataset/frames/wall_176x144.pcd
check "batch JSON lines onto a file that is not a batch result" 1 "notes.txt: line 1 is not a frame result" $D in/batch $SR --json in/notes.txt
check "a directory without frames" 1 "no_frames: no frames" $D in/no_frames --json out/none.jsonl
check "a frame one row high" 1 "one_row_100x1.u16: a 100x1 image; a depth frame needs at least 2 rows" $K in/one_row_100x1.u16 --width 100 --height 1
check "a NaN focal length" 1 "--fy must be a focal length of" $K in/frame.png --fy nan
check "a median window of 100000 pixels" 1 "--median-window is 100000, outside \\[-1, 31\\]" $K in/frame.png --median-window 100000
# Reruns find their frames however the input is spelled; more jobs than frames is fine.
check "agex_detect rerun as ./in/batch/" 0 "60 frames already in" $D ./in/batch/ $SR --json out/batch.jsonl
[ "$(wc -l < out/batch.jsonl)" = 60 ] || { echo "FAILED: the respelled rerun added lines" >&2; failures=$((failures + 1)); }
head -c -1 out/batch.jsonl > out/no_newline.jsonl  # the last line lost its newline
sed -i '$d' out/no_newline.jsonl && head -c -1 out/no_newline.jsonl > out/cut.jsonl
check "agex_detect rerun onto a file whose last line has no newline" 0 "59 frames already in" $D in/batch $SR --json out/cut.jsonl
[ "$(grep -c '^{.*}$' out/cut.jsonl)" = 60 ] || { echo "FAILED: the appended line was glued to the last one" >&2; failures=$((failures + 1)); }
check "agex_detect --jobs 100000" 0 "" $D in/batch $SR --json out/jobs.jsonl --jobs 100000
[ "$(wc -l < out/jobs.jsonl)" = 60 ] || { echo "FAILED: --jobs 100000 did not give 60 lines" >&2; failures=$((failures + 1)); }

# --force and outputs over what is not theirs: only an earlier output of the same kind is
# replaced, recognised by its content; inputs and unrelated files stay byte for byte.
mkdir -p in/loss/src in/loss/thesis in/two
cp in/dataset/frames/wall_176x144.pcd in/loss/src/a.pcd
cp in/dataset/frames/wall_176x144.pcd in/loss/src/b.pcd
echo "chapter 1" > in/loss/thesis/c.txt
echo "my own file" > in/mine.txt
cp -r in/dataset in/ds_with_notes && echo "my notes" > in/ds_with_notes/notes.txt
cp in/wall_176x144.u16 in/two/a.u16 && cp in/wall_176x144.u16 in/two/b.u16
"$BIN/agex_convert" u16 --input in/two --output in/ds_two $SR >/dev/null 2>&1
if [ -f "$SRC/../shared/data/mocap/cmu_131_01.bvh" ]; then
  cp "$SRC/../shared/data/mocap/cmu_131_01.bvh" in/walk.bvh
else
  cp in/truncated.bvh in/walk.bvh  # the output is refused before the motion is read
fi
(cd in && find . -type f -print0 | sort -z | xargs -0 sha256sum) > inputs.sha256
check "convert --force onto a directory holding its input and other files" 1 "in/loss: output would replace a directory that holds an input" $C pcd --input in/loss/src --output in/loss --force
check "convert --force onto a regular file" 1 "mine.txt: is a regular file, not an agex dataset" $C u16 --input in/wall_176x144.u16 $SR --output in/mine.txt --force
check "convert --force onto a directory that is not a dataset" 1 "thesis: is a directory without an agex dataset.json" $C pcd --input in/loss/src --output in/loss/thesis --force
check "synth --force onto a directory that is not a dataset" 1 "thesis: is a directory without an agex dataset.json" $S --motion in/walk.bvh --frames 2 --output in/loss/thesis --force
check "synth --force onto a dataset holding a file of someone else" 1 "ds_with_notes: holds notes.txt, which is not part of an agex dataset" $S --motion in/walk.bvh --frames 2 --output in/ds_with_notes --force
if [ -f "$SRC/../shared/data/mocap/cmu_131_01.bvh" ]; then  # a real motion: its dataset has part and person images
  $S --motion in/walk.bvh --frames 2 --output out/synth_again >/dev/null 2>&1
  check "synth --force onto its own earlier dataset" 0 "2 sr4000 frames" $S --motion in/walk.bvh --frames 2 --output out/synth_again --force
fi
$C u16 --input in/wall_176x144.u16 $SR --output out/replaced >/dev/null 2>&1
check "convert --force onto an earlier agex dataset" 0 "1 frames" $C u16 --input in/wall_176x144.u16 $SR --output out/replaced --force
check "one frame of a dataset, JSON over its labels" 1 "labels.csv: output would (overwrite an input|land inside the input dataset)" $D in/ds_two/frames/a.pcd --json in/ds_two/labels.csv
check "one frame of a dataset, overlay over another frame" 1 "b.pcd: output would (overwrite an input|land inside the input dataset)" $D in/ds_two/frames/a.pcd --overlay in/ds_two/frames/b.pcd
check "one frame, JSON over a file of another kind" 1 "mine.txt: exists and is not a JSON document of a frame" $D in/frame.png --json in/mine.txt
check "one frame, overlay over a file of another kind" 1 "mine.txt: exists and is not a PNG written by agex" $D in/frame.png --overlay in/mine.txt
sum_batch=$(sha256sum < out/batch.jsonl)
check "one frame, JSON over a JSON-lines results file" 1 "batch.jsonl: is a JSON-lines results file" $D in/frame.png --json out/batch.jsonl
[ "$(sha256sum < out/batch.jsonl)" = "$sum_batch" ] || { echo "FAILED: the JSON-lines file was replaced" >&2; failures=$((failures + 1)); }
$D in/frame.png --json out/single.json --overlay out/single.png >/dev/null 2>&1
check "one frame, JSON and overlay over those of an earlier run" 0 "" $D in/frame.png --json out/single.json --overlay out/single.png
grep -q '"frame"' out/single.json || { echo "FAILED: the earlier single-frame JSON was not replaced" >&2; failures=$((failures + 1)); }

# Two runs on one JSON-lines file at once, and reruns from elsewhere: complete, duplicate-free
# output, or a clear refusal.
# race CASE FILE: runs the batch twice at once onto FILE and checks the outcome.
race () {
  local what=$1 file=$2
  $D in/batch $SR --json "$file" > out/race1.log 2>&1 &
  local p1=$!
  $D in/batch $SR --json "$file" > out/race2.log 2>&1 &
  local p2=$!
  wait $p1; local s1=$?
  wait $p2; local s2=$?
  local lines unique refusal
  lines=$(wc -l < "$file") unique=$(grep -o '"frame":"[^"]*"' "$file" | sort -u | wc -l)
  refusal=$(cat out/race1.log out/race2.log | grep -E "error|already in" | head -1 | sed "s|$WORK/||g")
  echo "| $what | \`agex_detect in/batch $SR --json ${file#"$WORK/"}\`, twice at once | $s1, $s2 | $refusal |"
  for pair in "$s1 out/race1.log" "$s2 out/race2.log"; do
    set -- $pair
    if [ "$1" != 0 ] && ! grep -q "another agex_detect run is writing to this file" "$2"; then
      echo "FAILED: $what: exit $1 without the refusal:" >&2; tail -3 "$2" >&2; failures=$((failures + 1))
    fi
  done
  [ "$lines" = 60 ] && [ "$unique" = 60 ] || { echo "FAILED: $what: $lines lines, $unique frames (want 60)" >&2; failures=$((failures + 1)); }
}
race "two batch runs on one new --json file" out/race.jsonl
head -20 out/batch.jsonl > out/race_torn.jsonl && printf '{"frame":"torn' >> out/race_torn.jsonl
race "two resumes of a file with a torn last line" out/race_torn.jsonl
check "agex_detect rerun from another working directory" 0 "60 frames already in" env -C in $D batch $SR --json ../out/batch.jsonl
check "agex_detect rerun with the absolute path of in/batch" 0 "60 frames already in" $D "$WORK/in/batch" $SR --json out/batch.jsonl
[ "$(wc -l < out/batch.jsonl)" = 60 ] || { echo "FAILED: the reruns from elsewhere added lines" >&2; failures=$((failures + 1)); }
mkdir -p in/bad_batch && cp in/truncated.png in/bad_batch/a.png && cp in/truncated.png in/bad_batch/b.png
(cd in && find . -type f -print0 | sort -z | xargs -0 sha256sum) > inputs.sha256
check "batch whose first frame fails" 1 "truncated or not a PNG" $D in/bad_batch --json out/never.jsonl
[ ! -e out/never.jsonl ] || { echo "FAILED: a run that wrote no frame left out/never.jsonl" >&2; failures=$((failures + 1)); }

# Runs split over processes, and live sources.
$D in/batch $SR --shard 0/2 --json out/shard0.jsonl > /dev/null 2>&1
check "--shard 2/2" 1 "--shard takes K/N, the K-th of N parts with 0 <= K < N" $D in/batch $SR --shard 2/2 --json out/s.jsonl
check "--shard 1/0x" 1 "--shard takes K/N" $D in/batch $SR --shard 1/0x --json out/s.jsonl
check "--merge of a frame file" 1 "frame.png: line 1 is not a frame result of agex_detect" $D --merge in/frame.png --json out/merged.jsonl
check "--merge without the other half" 1 "30 of 60 frames are in no part \\(input positions 30, 31, 32, 33, 34, ...\\)" $D --merge out/shard0.jsonl --json out/merged.jsonl
[ ! -e out/merged.jsonl ] || { echo "FAILED: a refused merge wrote out/merged.jsonl" >&2; failures=$((failures + 1)); }
check "--merge onto an input part" 1 "shard0.jsonl: .*(input|read)" $D --merge out/shard0.jsonl --json out/shard0.jsonl
check "--device openni2:#9 (no such camera)" 1 "(no depth camera|cannot open the depth camera): tried openni2:#9" timeout 20 $D --device "openni2:#9" --json out/live.jsonl
[ ! -e out/live.jsonl ] || { echo "FAILED: a run without a camera left out/live.jsonl" >&2; failures=$((failures + 1)); }
check "--device kinect2" 1 "--device takes openni2, openni2:URI .* or replay:PATH" $D --device kinect2
check "--device replay: of a missing directory" 1 "missing: no such file or directory" $D --device replay:in/missing
check "--device replay:in/batch --fps 0" 1 "--fps must lie in \\[0.1, 1000\\]" $D --device replay:in/batch --fps 0
check "agex_eval coverage under --shard" 1 "only agex_eval detect shares its frames" $E coverage --dataset in/dataset --shard 0/2
check "agex_eval detect with a pipeline flag" 1 "--spur-iterations applies to agex_eval coverage, not to agex_eval 'detect'" \
  $E detect --dataset in/dataset --spur-iterations 0 --json out/d.json
check "agex_eval compare with a detect flag" 1 "--forest applies to agex_eval detect or parts" \
  $E compare --dataset in/dataset --forest in/dataset

# Parsers that would recurse without bound, and inputs that would block.
cp "$SRC/test/fuzz/regressions/model/nested_100000_deep_overflows_opencv_stack.yml" in/nested_model.yml
cp "$SRC/test/fuzz/regressions/imglab_xml/nested_50000_deep_overflowed_the_stack.xml" in/nested_imglab.xml
cp "$SRC/data/models/agex_people_detector.svm" in/people.svm
cp "$SRC/data/models/agex_people_detector.svm" "in/people@0.5.svm"
mkdir -p fifo && mkfifo fifo/frame.u16
(cd in && find . -type f -print0 | sort -z | xargs -0 sha256sum) > inputs.sha256
check "model nested 100,000 deep ([[[...)" 1 "nested_model.yml:3: nested more than 1000 levels deep" $D in/frame.png --model in/nested_model.yml --json out/a.json
check "the same model for agex_eval" 1 "nested_model.yml:3: nested more than 1000 levels deep" $E compare --dataset in/dataset --model-agex in/nested_model.yml
check "the same model for agex_eval detect" 1 "nested_model.yml:3: nested more than 1000 levels deep" $E detect --dataset in/dataset --model in/nested_model.yml
if [ -x "$BIN/agex_landmarks_train" ]; then
  check "imglab XML nested 50,000 deep, agex_landmarks_train" 1 "nested_imglab.xml:.*nested more than 64" $BIN/agex_landmarks_train --dataset in/nested_imglab.xml --out out/shape.dat
  check "the same XML for agex_landmarks_eval" 1 "nested_imglab.xml:.*nested more than 64" $BIN/agex_landmarks_eval --dataset in/nested_imglab.xml --model out/shape.dat
  check "agex_landmarks_train --combine, an offset of 7" 1 "--combine .*@7: the offset after '@' must be a number in \\[-5, 5\\]" \
    $BIN/agex_landmarks_train --combine in/people.svm --combine in/people.svm@7 --detector-out out/both.svm
  check "agex_landmarks_train --combine with --dataset" 1 "--combine trains nothing" \
    $BIN/agex_landmarks_train --combine in/people.svm --dataset in/nested_imglab.xml --out out/shape.dat --detector-out out/both.svm
  check "agex_landmarks_train --combine writing over a member" 1 "would overwrite an input" \
    $BIN/agex_landmarks_train --combine in/model.yml@0 --combine in/model.yml --detector-out in/model.yml
  check "agex_landmarks_train --combine over a file that is no detector" 1 "frame.png: exists and is not a people detector" \
    $BIN/agex_landmarks_train --combine in/people.svm --detector-out in/frame.png
  check "agex_landmarks_train --combine of a file that is no detector" 1 "model.yml: not an agex people detector" \
    $BIN/agex_landmarks_train --combine in/model.yml --detector-out out/both.svm
  check "agex_landmarks_train --combine, 10 members in all (5 ensembles of 2)" 1 "error: --combine: .*10 members in all, at most 8" \
    $BIN/agex_landmarks_train --combine in/people.svm --combine in/people.svm --combine in/people.svm \
    --combine in/people.svm --combine in/people.svm --detector-out out/both.svm
  check "agex_landmarks_train --combine of a file named with an '@'" 0 "out/at.svm: ensemble of 2" \
    $BIN/agex_landmarks_train --combine "in/people@0.5.svm" --detector-out out/at.svm
fi
check "a .u16 frame that is a FIFO" 1 "frame.u16: is a FIFO \\(named pipe\\), not a regular file" timeout 20 $D fifo/frame.u16 --json out/a.json

# Model settings are checked like the flags they mirror (file and key named).
sed 's/\\"mixed_window_radius\\":-\?[0-9]*,/\\"mixed_window_radius\\":1000000,/' in/model.yml > in/mixed_radius_model.yml
sed 's/\\"median_window\\":-\?[0-9]*,/\\"median_window\\":100000,/' in/model.yml > in/median_model.yml
sed 's/\\"k\\":16,/\\"k\\":100000000,/' in/model.yml > in/k_model.yml
sed 's/\\"delta_connected\\":[0-9.e-]*,/\\"delta_connected\\":-1,/' in/model.yml > in/delta_model.yml
for f in mixed_radius median k delta; do
  cmp -s in/model.yml "in/${f}_model.yml" && { echo "FAILED: in/${f}_model.yml: the setting was not changed" >&2; failures=$((failures + 1)); }
done
(cd in && find . -type f -print0 | sort -z | xargs -0 sha256sum) > inputs.sha256
check "model whose mixed_window_radius is 1e6" 1 "mixed_radius_model.yml.*mixed_window_radius" $D in/frame.png --model in/mixed_radius_model.yml --json out/a.json
check "model whose median_window is 1e5" 1 "median_model.yml.*median_window" $D in/frame.png --model in/median_model.yml --json out/a.json
check "model whose k is 1e8" 1 "k_model.yml.*\\bk\\b" $D in/frame.png --model in/k_model.yml --json out/a.json
check "model whose delta_connected is -1" 1 "delta_model.yml.*delta_connected" $D in/frame.png --model in/delta_model.yml --json out/a.json
check "--delta-connected 100" 1 "--delta-connected" $K in/frame.png --delta-connected 100
check "--min-separation -0.1" 1 "--min-separation" $K in/frame.png --min-separation -0.1

# Results that would be wrong without a word.
head -c $((320 * 240 * 2)) /dev/zero | tr '\0' '\7' > in/wall_320x240.u16
cp -r in/dataset in/ds_nan_tip
printf '%s\n%s\n' "$(head -1 in/dataset/labels.csv)" "wall_176x144,head,0,nan,nan,nan,nan,nan,nan,10,10,10,10,1,1" > in/ds_nan_tip/labels.csv
mkdir -p in/utf/séq in/utf/sèq in/take_a/take in/take_b/take
for d in in/utf/séq in/utf/sèq in/take_a/take in/take_b/take; do cp in/dataset/frames/wall_176x144.pcd "$d/"; done
(cd in && find . -type f -print0 | sort -z | xargs -0 sha256sum) > inputs.sha256
check "a 320x240 frame with the Kinect's 640x480 intrinsics" 1 "a 320x240 depth image, but the intrinsics .* are stated for 640x480" $D in/wall_320x240.u16 --width 320 --height 240 --json out/a.json
check "a 176x144 frame with the default intrinsics" 1 "a 176x144 depth image, but the intrinsics" $K in/wall_176x144.u16 --width 176 --height 144
check "a principal point outside the frame" 1 "principal point \\(cx 1000, cy 239.5\\) lies outside the 640x480 image" $D in/frame.png --cx 1000 --json out/a.json
check "agex_eval compare on a dataset without labels" 0 "AGEX_5 contains 0/0" $E compare --dataset in/dataset --json out/compare.json
if grep -q -- '-9223372036854775808' out/compare.json || [ "$(tr -d ' \n' < out/compare.json | grep -o '"fraction":null' | wc -l)" != 3 ]; then
  echo "FAILED: compare: empty classes are not null, or a count is not an integer:" >&2; grep -A3 contained out/compare.json | head -8 >&2
  failures=$((failures + 1))
fi
check "label with NaN tips marked visible" 1 "labels.csv:2: visible is 1 but the tip is not a number" $E coverage --dataset in/ds_nan_tip --json out/a.json
check "sequences séq and sèq" 0 "2 frames" $C pcd --input in/utf/séq in/utf/sèq --output out/utf
grep -q '"sequence": "séq"' out/utf/dataset.json && grep -q '"sequence": "sèq"' out/utf/dataset.json ||
  { echo "FAILED: the sequence names were not kept" >&2; failures=$((failures + 1)); }
check "two directories of one name" 1 "would both be sequence 'take'" $C pcd --input in/take_a/take in/take_b/take --output out/take
check "--depth-scale 0" 1 "--depth-scale must be a positive number" $K in/frame.png --depth-scale 0
check "--min-confidence nan" 1 "--min-confidence must lie in \\[0, 1\\]" $D in/frame.png --min-confidence nan

# Further cases, one file per concern (test/bad_inputs/cases/*.sh), in name order; each adds
# its inputs under in/ and calls hash_inputs before its checks.
for cases in "$SRC"/test/bad_inputs/cases/*.sh; do
  [ -e "$cases" ] || continue
  # shellcheck source=/dev/null
  source "$cases"
done

if [ "$failures" -gt 0 ]; then
  echo "$failures bad-input case(s) failed" >&2
  exit 1
fi
echo "all bad-input cases behave as documented" >&2
