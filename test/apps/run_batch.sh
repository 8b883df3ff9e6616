#!/usr/bin/env bash
# Batch runs spread over processes give what one process gives: agex_detect under
# mpirun -n 2 (and after an interrupted run, resumed), agex_detect --shard K/N joined with
# --merge, agex_eval detect under mpirun -n 2 and as --shard parts joined with --merge. Same
# frames, same order, same detections and figures; only the timings ("ms") may differ.
# Frames: Bonn frames from ../shared when it is there, else the bundled frame and the
# bad-input frames (copies under several names); agex_eval needs the Bonn labels (skipped
# without them).
# Usage: run_batch.sh BIN_DIR SOURCE_DIR WORK_DIR SHARED_DATA_DIR [MPIRUN]
set -u
bin=$1 src=$2 work=$3 shared=$4 mpirun=${5:-}
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
rm -rf "$work" && mkdir -p "$work/frames" || exit 1
cd "$work" || exit 1

if [ -d "$shared/bonn/depth/1" ]; then
  for f in 000 003 006 009 012 015 018 021; do cp "$shared/bonn/depth/1/$f.png" "frames/s1_$f.png"; done
  cp "$shared/bonn/depth/4/010.png" frames/s4_010.png
  cp "$shared/bonn/depth/7/020.png" frames/s7_020.png
  echo "frames: 10 Bonn frames from $shared/bonn"
else
  for f in a b c d e f; do cp "$src/data/frames/bonn_1_002.png" "frames/bonn_$f.png"; done
  cp "$src/test/bad_inputs/inputs/all_invalid_640x480.png" "$src/test/bad_inputs/inputs/one_pixel_specks_640x480.png" frames/
  echo "frames: the bundled frame and two bad-input frames ($shared/bonn not found)"
fi
frames=$(ls frames | wc -l)

# The reference: one process, one thread, so the lines are in input order.
"$bin/agex_detect" frames --json single.jsonl 2> single.log || fail "single run failed: $(cat single.log)"
[ "$(wc -l < single.jsonl)" -eq "$frames" ] || fail "single run wrote $(wc -l < single.jsonl) lines for $frames frames"
untimed() { sed 's/"ms":{[^}]*}//' "$1"; }
same_as_single() {  # FILE WHAT
  if ! diff <(untimed single.jsonl) <(untimed "$1") > /dev/null; then
    fail "$2: $1 differs from the single-process run"
    diff <(untimed single.jsonl | cut -c1-120) <(untimed "$1" | cut -c1-120) | head -10
  fi
}

# --shard: three parts, two threads each (their lines in finish order), joined in input order.
for k in 0 1 2; do
  "$bin/agex_detect" frames --shard "$k/3" --jobs 2 --json "part$k.jsonl" 2> /dev/null || fail "--shard $k/3 failed"
done
grep -q '"batch":{"frames":'"$frames"',"index":' part0.jsonl || fail "shard lines carry no batch index"
"$bin/agex_detect" --merge part2.jsonl part1.jsonl part0.jsonl --json merged.jsonl 2> merge.log ||
  fail "--merge failed: $(cat merge.log)"
same_as_single merged.jsonl "--shard K/3 + --merge"
grep -q '"batch"' merged.jsonl && fail "the merged lines still carry their batch index"
# A part missing: refused, naming the frames no part holds; the earlier merge stays.
cp merged.jsonl merged.before
if "$bin/agex_detect" --merge part0.jsonl part2.jsonl --json fresh.jsonl 2> missing.log; then
  fail "--merge without part 1 succeeded"
fi
grep -q "in no part" missing.log || fail "a missing part is not named: $(cat missing.log)"
[ -e fresh.jsonl ] && fail "a refused merge wrote its output"
# Merging again onto the merged file changes nothing.
"$bin/agex_detect" --merge part0.jsonl part1.jsonl part2.jsonl --json merged.jsonl 2> /dev/null || fail "second merge failed"
cmp -s merged.jsonl merged.before || fail "merging again changed the merged file"

if [ -z "$mpirun" ]; then
  echo "note: no mpirun (built without MPI): the mpirun runs are not checked"
else
  # In a sanitizer build, LeakSanitizer would report what OpenMPI's components (shared objects
  # it loads and unloads itself, so the reports name no module to suppress) keep after
  # MPI_Finalize; the ranks run without leak detection, which the single-process runs above
  # and the rest of the suite keep. Other sanitizer reports still fail the run.
  run_mpi() { ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0" "$mpirun" -n 2 --oversubscribe \
    $( [ "$(id -u)" = 0 ] && echo --allow-run-as-root ) "$@"; }
  run_mpi "$bin/agex_detect" frames --json mpi.jsonl > mpi.log 2>&1 || fail "mpirun -n 2 agex_detect failed: $(cat mpi.log)"
  same_as_single mpi.jsonl "mpirun -n 2"
  ls mpi.jsonl.part-* > /dev/null 2>&1 && fail "the parts were left behind after the merge"

  # Interrupted: a bad frame in rank 1's share stops it; nothing is merged, the parts stay;
  # with the frame repaired, the rerun does only what is left and gives the same result.
  victim=$(ls frames | sed -n "$((frames * 3 / 4 + 1))p")
  cp "frames/$victim" victim.png
  echo "not a png" > "frames/$victim"
  if run_mpi "$bin/agex_detect" frames --json resumed.jsonl > broken.log 2>&1; then
    fail "a run with a bad frame succeeded"
  fi
  grep -q "rank 1: .*$victim" broken.log || fail "the bad frame is not named by its rank: $(grep error broken.log)"
  [ -e resumed.jsonl ] && fail "a failed run merged"
  ls resumed.jsonl.part-0-of-2 resumed.jsonl.part-1-of-2 > /dev/null 2>&1 || fail "the parts of the failed run are gone"
  cp victim.png "frames/$victim"
  run_mpi "$bin/agex_detect" frames --json resumed.jsonl > resume.log 2>&1 || fail "the resumed run failed: $(cat resume.log)"
  grep -q "already in resumed.jsonl.part-1-of-2" resume.log || fail "the rerun did not resume rank 1's part"
  same_as_single resumed.jsonl "mpirun -n 2, interrupted and resumed"
  # And a rerun with everything done changes nothing.
  cp resumed.jsonl resumed.before
  run_mpi "$bin/agex_detect" frames --json resumed.jsonl > again.log 2>&1 || fail "a rerun of a finished run failed"
  cmp -s resumed.jsonl resumed.before || fail "a rerun of a finished run changed its output"
fi

# agex_eval detect: the figures of one process, of two ranks and of three shards merged.
if [ -d "$shared/bonn/depth/1" ]; then
  "$bin/agex_convert" bonn --input "$shared/bonn" --sequences 1 --output bonn1 > /dev/null 2>&1 || fail "agex_convert failed"
  "$bin/agex_eval" detect --dataset bonn1 --json eval_single.json > /dev/null 2>&1 || fail "agex_eval detect failed"
  report() { grep -v '"ms_per_frame_median"' "$1"; }
  for k in 0 1 2; do
    "$bin/agex_eval" detect --dataset bonn1 --shard "$k/3" --json "eval_part$k.json" > /dev/null 2>&1 || fail "agex_eval --shard $k/3 failed"
  done
  "$bin/agex_eval" detect --merge eval_part1.json eval_part0.json eval_part2.json --json eval_merged.json > /dev/null 2>&1 ||
    fail "agex_eval detect --merge failed"
  diff <(report eval_single.json) <(report eval_merged.json) > /dev/null || fail "agex_eval --shard + --merge differs from one run"
  "$bin/agex_eval" detect --merge eval_part1.json eval_part0.json --json eval_two.json > two.log 2>&1 &&
    fail "agex_eval --merge without shard 2 succeeded"
  grep -q "shard(s) 2 of 3 missing" two.log || fail "the missing shard is not named: $(cat two.log)"
  if [ -n "$mpirun" ]; then
    run_mpi "$bin/agex_eval" detect --dataset bonn1 --json eval_mpi.json > eval_mpi.log 2>&1 || fail "mpirun agex_eval failed: $(cat eval_mpi.log)"
    diff <(report eval_single.json) <(report eval_mpi.json) > /dev/null || fail "agex_eval under mpirun -n 2 differs from one run"
  fi
else
  echo "note: $shared/bonn not found: agex_eval's shares are not checked"
fi

if [ $failures -gt 0 ]; then
  echo "$failures problem(s)"
  exit 1
fi
echo "batch runs: the same results split over processes as in one"
