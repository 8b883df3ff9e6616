#!/usr/bin/env bash
# scripts/set_model_pipeline.py writes only its new copy: never over its input, never over an
# existing file, nothing for an unknown setting; the copy it writes is a model agex_detect loads.
# Usage: run_set_model_pipeline.sh BIN_DIR SOURCE_DIR WORK_DIR
set -u
bin=$1 src=$2 work=$3
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
rm -rf "$work" && mkdir -p "$work" && cd "$work" || exit 1
script=$src/scripts/set_model_pipeline.py
cp "$src/data/models/agex_bonn_agex.yml" m.yml
cp m.yml m.orig
echo "not a model of ours" > other.txt
cp other.txt other.orig

python3 "$script" m.yml m.yml k=3 2> same.log && fail "writing over its input succeeded"
cmp -s m.yml m.orig || fail "the input changed"
python3 "$script" m.yml other.txt k=3 2> other.log && fail "writing over an existing file succeeded"
cmp -s other.txt other.orig || fail "an existing file changed"
grep -q "exists" other.log || fail "the refusal does not say why: $(cat other.log)"
python3 "$script" m.yml bogus.yml no_such_setting=1 2> bogus.log && fail "an unknown setting was accepted"
[ -e bogus.yml ] && fail "a refused run wrote its output"
python3 "$script" m.yml copy.yml k=3 || fail "a good run failed"
cmp -s m.yml m.orig || fail "the input changed on a good run"
grep -q '\\"k\\":3,' copy.yml || fail "the copy does not carry k = 3"
"$bin/agex_detect" "$src/data/frames/bonn_1_002.png" --model copy.yml --json copy.json > detect.log 2>&1 \
  || fail "agex_detect refused the copy: $(cat detect.log)"
ls ./*.tmp > /dev/null 2>&1 && fail "a temporary file was left behind"

[ "$failures" = 0 ] && echo "set_model_pipeline: all checks passed"
exit "$failures"
