#!/usr/bin/env bash
# The long batch run of doc/bad_inputs.md: agex_detect over thousands of synthetic frames in
# the AGEX_SANITIZE build (LeakSanitizer on), sampling its resident memory as it goes.
#   test/sanitizers/long_batch_run.sh BUILD_DIR DATASET_DIR OUT_DIR [SECONDS_BETWEEN_SAMPLES]
# Make the dataset first, e.g.
#   build/bin/agex_synth --motion ../shared/data/mocap/*.bvh --frames 3000 --sensor sr4000 \
#       --seed 7 --output /tmp/agex_long
# Writes OUT_DIR/detections.jsonl and OUT_DIR/rss.csv (seconds, frames done, VmRSS kB); prints
# the exit status (a leak or sanitizer report makes it non-zero) and the memory over time.
set -u
BUILD=$1 DATASET=$2 OUT=$3 EVERY=${4:-2}
mkdir -p "$OUT"
rm -f "$OUT/detections.jsonl"
echo "seconds,frames,rss_kb" > "$OUT/rss.csv"
start=$(date +%s)
"$BUILD/bin/agex_detect" "$DATASET" --json "$OUT/detections.jsonl" 2> "$OUT/stderr.log" &
pid=$!
while kill -0 "$pid" 2>/dev/null; do
  rss=$(awk '/^VmRSS/ {print $2}' "/proc/$pid/status" 2>/dev/null)
  frames=$(cat "$OUT/detections.jsonl" 2>/dev/null | wc -l)
  [ -n "$rss" ] && echo "$(( $(date +%s) - start )),$frames,$rss" >> "$OUT/rss.csv"
  sleep "$EVERY"
done
wait "$pid"
status=$?
echo "agex_detect exit status: $status after $(( $(date +%s) - start )) s, $(wc -l < "$OUT/detections.jsonl") frames"
grep -E "ERROR: (Address|Leak)Sanitizer|runtime error" "$OUT/stderr.log" | head -5
# Memory at each tenth of the frames.
awk -F, 'NR > 1 { rows[++n] = $0 } END {
  if (n == 0) exit
  for (q = 1; q <= 10; ++q) { i = int (n * q / 10); if (i < 1) i = 1; split (rows[i], f, ","); printf "  %3d s  %5d frames  %7.1f MB\n", f[1], f[2], f[3] / 1024 }
}' "$OUT/rss.csv"
exit "$status"
