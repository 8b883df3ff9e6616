#!/usr/bin/env bash
# agex_detect --device without a camera: a directory replayed at a set frame rate through the
# same frame-source interface as a camera. Faster than the detector: frames are dropped, not
# queued, and counted (processed + dropped = replayed, the newest frame always processed);
# slow enough: none dropped; Ctrl-C (SIGINT) and SIGTERM stop it cleanly (exit 0, every line
# whole, a summary); no camera: a clear error naming what was tried.
# Usage: run_live.sh BIN_DIR SOURCE_DIR WORK_DIR
set -u
bin=$1 src=$2 work=$3
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
rm -rf "$work" && mkdir -p "$work/frames" || exit 1
cd "$work" || exit 1
for i in 00 01 02 03 04 05 06 07 08 09 10 11; do cp "$src/data/frames/bonn_1_002.png" "frames/f$i.png"; done
cp "$src/test/bad_inputs/inputs/all_invalid_640x480.png" frames/f12.png
frames=13
field() { sed -n "s/.*\"$1\":\([0-9.e+-]*\).*/\1/p" "$2"; }  # FIELD FILE: the field of each line

# 1. 1000 frames per second, far faster than the detector: most frames dropped.
"$bin/agex_detect" --device replay:frames --fps 1000 --json fast.jsonl 2> fast.log || fail "fast replay failed: $(cat fast.log)"
processed=$(wc -l < fast.jsonl)
dropped=$(field dropped fast.jsonl | tail -1)
[ "$processed" -ge 1 ] || fail "fast replay processed nothing"
[ "${dropped:-0}" -ge 1 ] || fail "fast replay dropped nothing ($processed frames processed)"
[ $((processed + ${dropped:-0})) -eq $frames ] || fail "processed $processed + dropped $dropped != $frames replayed"
[ "$(field sequence fast.jsonl | tail -1)" = $((frames - 1)) ] || fail "the newest frame was not processed"
grep -q "$processed frames processed, $dropped dropped" fast.log || fail "no summary: $(cat fast.log)"
sequences=$(field sequence fast.jsonl | tr '\n' ' ')
sorted=$(field sequence fast.jsonl | sort -n | tr '\n' ' ')
[ "$sequences" = "$sorted" ] || fail "sequences out of order: $sequences"

# 2. Two frames per second: the detector keeps up, nothing dropped; JSON lines on stdout.
"$bin/agex_detect" --device replay:frames --fps 2 > slow.jsonl 2> slow.log || fail "slow replay failed: $(cat slow.log)"
[ "$(wc -l < slow.jsonl)" -eq $frames ] || fail "slow replay wrote $(wc -l < slow.jsonl) lines for $frames frames"
[ "$(field dropped slow.jsonl | sort -u | tr -d '\n')" = 0 ] || fail "slow replay dropped frames: $(field dropped slow.jsonl | tr '\n' ' ')"
grep -q '"frame":"frames/f05.png"' slow.jsonl || fail "frames are not named as agex_detect names them"
grep -q '"timestamp":2.5' slow.jsonl || fail "no replay timestamps (frame 5 at 2.5 s)"

# 3. Stopped by SIGINT (Ctrl-C) and by SIGTERM: exit 0, whole lines, a summary.
set -m  # background jobs keep SIGINT (a non-interactive shell would ignore it for them)
for signal in INT TERM; do
  "$bin/agex_detect" --device replay:frames --fps 2 --json "stop_$signal.jsonl" 2> "stop_$signal.log" &
  pid=$!
  sleep 2
  kill -s "$signal" "$pid"
  wait "$pid"
  rc=$?
  [ $rc -eq 0 ] || fail "SIG$signal: exit $rc: $(cat "stop_$signal.log")"
  lines=$(wc -l < "stop_$signal.jsonl" 2> /dev/null || echo 0)
  [ "$lines" -ge 1 ] && [ "$lines" -lt $frames ] || fail "SIG$signal: $lines lines (expected some, not all $frames)"
  grep -v -q '}$' "stop_$signal.jsonl" && fail "SIG$signal: a torn line"
  grep -q "stopped by a signal" "stop_$signal.log" || fail "SIG$signal: no summary saying so: $(cat "stop_$signal.log")"
done
set +m

# 4. No camera, or no such source: a clear error naming what was tried, exit 1.
if "$bin/agex_detect" --device openni2 > none.jsonl 2> none.log; then
  echo "note: a depth camera is connected; the no-camera message is not checked"
else
  grep -q "tried openni2" none.log || fail "no camera: the message does not say what was tried: $(cat none.log)"
fi
"$bin/agex_detect" --device kinect 2> bad.log && fail "--device kinect was accepted"
grep -q "openni2, openni2:URI" bad.log || fail "a bad --device does not say what is expected: $(cat bad.log)"
"$bin/agex_detect" --device replay:missing_dir 2> missing.log && fail "a missing replay source was accepted"
grep -q "missing_dir" missing.log || fail "a missing replay source is not named: $(cat missing.log)"
"$bin/agex_detect" frames --device replay:frames 2> both.log && fail "--device with INPUT was accepted"

if [ $failures -gt 0 ]; then
  echo "$failures problem(s)"
  exit 1
fi
echo "live runs: frames as they arrive, drops counted, stopped cleanly"
