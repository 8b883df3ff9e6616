#!/usr/bin/env bash
# scripts/leak_checker_crashes.py: the sanitizer suite reruns a failed test only when the test
# passed and LeakSanitizer's tracer crashed at exit; any other failure beside it stays a failure.
# Usage: run_leak_checker_crashes.sh SOURCE_DIR WORK_DIR
set -u
src=$1 work=$2
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
rm -rf "$work" && mkdir -p "$work" || exit 1
crash='[  PASSED  ] 1 test.
Tracer caught signal 11: addr=0x22e0 pc=0x558187713dda sp=0x7ffb807fbd40
==3930==LeakSanitizer has encountered a fatal error.'
case_xml() {  # NAME STATUS OUTPUT
  printf '\t<testcase name="%s" classname="%s" time="1" status="%s">\n' "$1" "$1" "$2"
  [ "$2" = fail ] && printf '\t\t<failure message=""/>\n'
  printf '\t\t<system-out>%s\n</system-out>\n\t</testcase>\n' "$3"
}
report() {  # FILE, then NAME STATUS OUTPUT triples
  local file=$1; shift
  { echo '<?xml version="1.0" encoding="UTF-8"?>'; echo '<testsuite name="(empty)" tests="3">'
    while [ $# -ge 3 ]; do case_xml "$1" "$2" "$3"; shift 3; done; echo '</testsuite>'; } > "$file"
}
expect() {  # EXIT_CODE FILE WHAT
  python3 "$src/scripts/leak_checker_crashes.py" "$2" > "$work/out" 2>&1
  local got=$?
  [ "$got" = "$1" ] || fail "$3: exit $got, expected $1: $(cat "$work/out")"
}
report "$work/only_crashes.xml" A.Passes run '[  PASSED  ] 1 test.' B.Crashes fail "$crash" C.Crashes fail "$crash"
expect 0 "$work/only_crashes.xml" "two tracer crashes after passing tests"
grep -q "B.Crashes: passed, then" "$work/out" || fail "the crashed test is not named: $(cat "$work/out")"

report "$work/with_real.xml" B.Crashes fail "$crash" D.Fails fail '[  FAILED  ] 1 test, listed below:'
expect 1 "$work/with_real.xml" "a tracer crash beside a failed test"
grep -q "D.Fails: a real failure" "$work/out" || fail "the real failure is not named: $(cat "$work/out")"

report "$work/leak.xml" E.Leaks fail "$crash
==1==ERROR: LeakSanitizer: detected memory leaks"
expect 1 "$work/leak.xml" "a leak report"
report "$work/ub.xml" F.Ub fail "x.cpp:3:5: runtime error: signed integer overflow
$crash"
expect 1 "$work/ub.xml" "an undefined-behaviour report"
report "$work/not_gtest.xml" G.Script fail 'Tracer caught signal 11: addr=0x0
==1==LeakSanitizer has encountered a fatal error.'
expect 1 "$work/not_gtest.xml" "a crash without a passed GoogleTest run"
report "$work/none.xml" A.Passes run '[  PASSED  ] 1 test.'
expect 1 "$work/none.xml" "a report without failures"
printf '<testsuite><testcase' > "$work/broken.xml"
expect 2 "$work/broken.xml" "a truncated report"
expect 2 "$work/missing.xml" "a missing report"
grep -q "missing.xml" "$work/out" || fail "the missing report is not named: $(cat "$work/out")"
[ "$failures" = 0 ] && echo "all cases passed"
exit $((failures > 0))
