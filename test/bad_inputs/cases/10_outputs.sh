# Sourced by run_bad_inputs.sh. Every app that writes a file: an output may replace only an
# earlier output of the same kind, recognised by its content; the user's files (kept under in/,
# so that the checksums prove them unchanged) stay byte for byte. Outputs that belong together
# are written as one set.

mkdir -p in/own/masks in/own/images in/own/overlays in/own/plots in/own/images_png
echo "my notes" > in/own/notes.txt
printf '{"threads": 4}\n' > in/own/config.json
cp in/frame.png in/own/photo.png  # a PNG agex did not write
cp "$SRC/data/images/five_people.jpg" in/people.jpg
cp in/people.jpg in/own/images/a.jpg && cp in/all_invalid_640x480.png in/own/masks/a.png
cp in/frame.png in/own/overlays/a.png && cp in/frame.png in/own/plots/precision_recall.png
cp in/frame.png in/own/plots/compare_head.png
cp in/frame.png in/own/images_png/people.png
cp "$SRC/data/models/agex_contour_landmarks.dat" in/contour_landmarks.dat
printf "<?xml version='1.0'?>\n<dataset>\n<images>\n<image file='../people.jpg'>\n</image>\n</images>\n</dataset>\n" \
  > in/own/empty_dataset.xml
hash_inputs

check "agex_bench --json over the user's notes" 1 "notes.txt: exists and is not a JSON object" \
  $BIN/agex_bench in/frame.png --json in/own/notes.txt
check "agex_bench --json over another JSON file" 1 "config.json: exists and is a JSON object without" \
  $BIN/agex_bench in/frame.png --json in/own/config.json
check "agex_train --out over the user's notes" 1 "notes.txt: exists and is not an agex model" \
  $T --dataset in/dataset --out in/own/notes.txt
check "agex_eval --json over another JSON file" 1 "config.json: exists and is a JSON object with none of the keys of an agex_eval report" \
  $E coverage --dataset in/dataset --json in/own/config.json
check "agex_eval compare --plots over the user's PNG" 1 "compare_head.png: exists and is not a PNG written by agex" \
  $E compare --dataset in/dataset --plots in/own/plots
check "agex_eval detect --plots over the user's PNG" 1 "precision_recall.png: exists and is not a PNG written by agex" \
  $E detect --dataset in/dataset --plots in/own/plots
if [ -x "$BIN/agex_landmarks" ]; then
  L=$BIN/agex_landmarks
  check "agex_landmarks --json over the user's notes" 1 "notes.txt: exists and is not a JSON object" \
    $L in/people.jpg --json in/own/notes.txt
  check "agex_landmarks --json over another JSON file" 1 "config.json: exists and is a JSON object without \"frames\"" \
    $L in/people.jpg --json in/own/config.json
  check "agex_landmarks --json-lines over the user's notes" 1 "notes.txt: exists and its line 1 is not a JSON line" \
    $L in/people.jpg --json-lines in/own/notes.txt
  check "agex_landmarks --overlay over the user's PNG" 1 "photo.png: exists and is not a PNG written by agex" \
    $L in/people.jpg --overlay in/own/photo.png
  $L in/people.jpg --json out/l.json --json-lines out/l.jsonl --overlay out/l.png >/dev/null 2>&1
  check "agex_landmarks over its own earlier outputs" 0 "people" \
    $L in/people.jpg --json out/l.json --json-lines out/l.jsonl --overlay out/l.png
  grep -q '"frames"' out/l.json || { echo "FAILED: agex_landmarks wrote no JSON over its own" >&2; failures=$((failures + 1)); }
  check "agex_annotate masks --out over the user's notes" 1 "notes.txt: exists and is not an imglab dataset written by agex_annotate" \
    $BIN/agex_annotate masks --images in/own/images --masks in/own/masks --out in/own/notes.txt
  check "agex_annotate masks --overlay-dir over the user's PNG" 1 "overlays/a.png: exists and is not a PNG written by agex" \
    $BIN/agex_annotate masks --images in/own/images --masks in/own/masks --out out/ann.xml --overlay-dir in/own/overlays
  [ ! -e out/ann.xml ] || { echo "FAILED: a refused agex_annotate wrote out/ann.xml" >&2; failures=$((failures + 1)); }
  check "agex_landmarks_train --out over the user's notes" 1 "notes.txt: exists and is not a shape predictor" \
    $BIN/agex_landmarks_train --dataset in/own/empty_dataset.xml --out in/own/notes.txt
  check "agex_landmarks_train --detector-out over the user's notes" 1 "notes.txt: exists and is not a people detector" \
    $BIN/agex_landmarks_train --dataset in/own/empty_dataset.xml --out out/shape.dat --detector-out in/own/notes.txt
  check "agex_landmarks_eval --json over another JSON file" 1 "config.json: exists and is a JSON object without" \
    $BIN/agex_landmarks_eval --dataset in/own/empty_dataset.xml --model in/contour_landmarks.dat \
    --no-detector --json in/own/config.json
  check "agex_landmarks_eval --overlay-dir over the user's PNG" 1 "people.png: exists and is not a PNG written by agex" \
    $BIN/agex_landmarks_eval --dataset in/own/empty_dataset.xml --model in/contour_landmarks.dat \
    --no-detector --overlay-dir in/own/images_png
fi

# Two runs writing one set of outputs (JSON, overlay, part map) at once, from different frames:
# the set on disk must be one run's whole set. Each run's own set is known from a run alone.
cp in/frame.png in/frame_b.png && cp in/one_pixel_specks_640x480.png in/frame_c.png
hash_inputs
set_of () { echo "$(grep -o '"frame": *"[^"]*"' "$1/j.json" | sed 's/.*"\([^"]*\)"$/\1/') $(sha256sum < "$1/o.png" | cut -c1-16) $(sha256sum < "$1/p.png" | cut -c1-16)"; }
mkdir -p out/set_b out/set_c out/set
for f in b c; do
  $D in/frame_$f.png --json out/set_$f/j.json --overlay out/set_$f/o.png --parts-overlay out/set_$f/p.png >/dev/null 2>&1
done
want_b=$(set_of out/set_b) want_c=$(set_of out/set_c) mixed=0
for trial in $(seq 1 12); do
  $D in/frame_b.png --json out/set/j.json --overlay out/set/o.png --parts-overlay out/set/p.png >/dev/null 2>&1 &
  p1=$!
  $D in/frame_c.png --json out/set/j.json --overlay out/set/o.png --parts-overlay out/set/p.png >/dev/null 2>&1 &
  p2=$!
  wait $p1 $p2
  got=$(set_of out/set)
  [ "$got" = "$want_b" ] || [ "$got" = "$want_c" ] || mixed=$((mixed + 1))
done
echo "| two agex_detect runs writing one set (--json, --overlay, --parts-overlay), 12 times | \`agex_detect in/frame_b.png ... & agex_detect in/frame_c.png ...\` | 0, 0 | $mixed of 12 sets mixed |"
[ "$mixed" = 0 ] || { echo "FAILED: $mixed of 12 concurrent sets were mixed" >&2; failures=$((failures + 1)); }

# Inputs that would block or run away.
mkfifo fifo/video.avi
check "agex_landmarks --video of a FIFO" 1 "video.avi: is a FIFO \\(named pipe\\), not a regular file" \
  timeout 20 $BIN/agex_landmarks --video fifo/video.avi
check "--device replay: --fps 1e-10 (overflowed the schedule)" 1 "--fps must lie in \\[0.1, 1000\\]" \
  $D --device replay:in/batch --fps 1e-10
check "--device replay: --fps 1e-9 (31 years a frame)" 1 "--fps must lie in \\[0.1, 1000\\]" \
  $D --device replay:in/batch --fps 1e-9
check "--cascade-min-confidence 1 (every candidate rejected)" 1 "--cascade-min-confidence must lie in \\[0, 1\\)" \
  $D in/frame_b.png --cascade-min-confidence 1
check "--cascade-min-confidence nan" 1 "cascade-min-confidence" \
  $D in/frame_b.png --cascade-min-confidence nan
check "--cascade-miss-rate 0.6" 1 "--cascade-miss-rate must lie in \\[0, 0.5\\]" \
  $D in/frame_b.png --cascade-miss-rate 0.6
check "--tip-radius 0.6" 1 "--tip-radius must lie in \\[0, 0.5\\] metres" \
  $D in/frame_b.png --tip-radius 0.6
check "--tip-min-confidence 0" 1 "--tip-min-confidence must lie in \\(0, 1\\]" \
  $D in/frame_b.png --tip-min-confidence 0
check "--window-weight 1.5" 1 "--window-weight must lie in \\[0, 1\\]" \
  $D in/frame_b.png --window-weight 1.5
check "--window-model of a fused model (not a sliding window)" 1 "is a fused model, but a sliding-window model is needed here" \
  $D in/frame_b.png --window-model in/model.yml
check "--window-model that is missing" 1 "in/no_such_sw.yml: model file not found" \
  $D in/frame_b.png --window-model in/no_such_sw.yml
check "--window-model with an AGEX-point model" 1 "--window-model rescores a fused model's candidates" \
  $D in/frame_b.png --model in/agex_model.yml --window-model in/agex_bonn_sw.yml
check "--window-weight without a window model" 1 "--window-weight needs a window model" \
  $D in/frame_b.png --model in/agex_model.yml --window-weight 0.5
check "agex_train --window-model without --fused" 1 "--window-model is for --fused" \
  $T --dataset in/dataset --out out/sw_window.yml --window-model in/agex_bonn_sw.yml
check "agex_train --window-weight without --window-model" 1 "--window-weight is for --window-model" \
  $T --dataset in/dataset --fused --forest in/agex_bonn_forest.agexforest --window-weight 0.5 --out out/fw.yml
check "agex_train --fused --window-model MODEL --out MODEL" 1 "is --out: the fused model would replace it" \
  $T --dataset in/dataset --fused --forest in/agex_bonn_forest.agexforest --window-model out/fw.yml --out out/fw.yml
check "agex_train --cascade-for a fused model with the AGEX-point flags" 1 "--cascade-for in/model.yml: a model of the fused detector, and these flags collect agex examples" \
  $T --dataset in/dataset --out out/cascade.yml --cascade-for in/model.yml
check "agex_train --cascade-for MODEL --out MODEL (over its own input)" 1 "model.yml: output would overwrite an input file" \
  $T --dataset in/dataset --out in/model.yml --cascade-for in/model.yml

# Reports of --shard runs whose numbers do not fit what they count, and merged results lines
# that are not whole: each refusal names the file and the field.
$E detect --dataset in/dataset --shard 0/1 --json out/shard_0_of_1.json >/dev/null 2>&1
sed 's/"count": *1\b/"count": 2808348672/' out/shard_0_of_1.json > in/shard_count_wraps.json
python3 - out/shard_0_of_1.json in/bands_not_a_list.json <<'PY'
import json, sys
doc = json.load(open(sys.argv[1]))
doc["state"]["persons"]["bands"] = "none"
json.dump(doc, open(sys.argv[2], "w"))
PY
$D in/batch $SR --shard 0/2 --json out/part0.jsonl >/dev/null 2>&1
sed '1s/"frame":"[^"]*"/"frame":""/' out/part0.jsonl > in/part_empty_frame.jsonl
sed '1s/"detections":\[[^]]*\]/"detections":"none"/' out/part0.jsonl > in/part_detections_none.jsonl
hash_inputs
check "agex_eval --merge of a shard whose count wraps past int" 1 "shard_count_wraps.json: \"shard\" says part 0 of 2808348672" \
  $E detect --merge in/shard_count_wraps.json --json out/merged_report.json
check "agex_eval --merge with --plots over the user's PNG" 1 "precision_recall.png: exists and is not a PNG written by agex" \
  $E detect --merge out/shard_0_of_1.json --json out/merged_report.json --plots in/own/plots
check "agex_eval --merge of a state whose bands are not a list" 1 "bands_not_a_list.json: person evaluation state \"bands\" must be a list" \
  $E detect --merge in/bands_not_a_list.json --json out/merged_report.json
check "agex_detect --merge of a line with \"frame\": \"\"" 1 "part_empty_frame.jsonl: line 1: \"frame\" is empty" \
  $D --merge in/part_empty_frame.jsonl --json out/merged_lines.jsonl
check "agex_detect --merge of a line with \"detections\": \"none\"" 1 "part_detections_none.jsonl: line 1: \"detections\" must be a list" \
  $D --merge in/part_detections_none.jsonl --json out/merged_lines.jsonl
[ ! -e out/merged_report.json ] && [ ! -e out/merged_lines.jsonl ] || { echo "FAILED: a refused merge wrote its output" >&2; failures=$((failures + 1)); }

# A flag is its whole name: boost took --mode for --model and read a model nobody named.
check "a prefix of a flag (--mode for --model)" 1 "unrecognised option '--mode'" $D in/frame.png --mode forest --json out/a.json
