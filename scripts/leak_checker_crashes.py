#!/usr/bin/env python3
"""Whether every failure in a ctest JUnit report is LeakSanitizer's own tracer crashing at exit.

LeakSanitizer stops the process with a tracer thread before it looks for leaks; a worker thread
that is still exiting at that moment (dlib keeps its pooled threads until exit) can crash the
tracer: "Tracer caught signal 11 ... LeakSanitizer has encountered a fatal error". The test has
passed by then and no leak check was made, so the suite reruns such tests once instead of
reporting a failure that says nothing about the code.

Usage: leak_checker_crashes.py JUNIT_XML
Prints the failed tests and why each is or is not such a crash. Exits 0 when at least one test
failed and every failed test is a GoogleTest test whose tests all passed before the tracer
crashed, 1 otherwise, 2 when the report cannot be read.
"""
import sys
import xml.etree.ElementTree as ElementTree

TRACER_CRASH = "LeakSanitizer has encountered a fatal error"
# Anything a sanitizer or GoogleTest reports about the code itself makes a failure real.
REAL_FAILURE_SIGNS = (
    "ERROR: AddressSanitizer",
    "ERROR: LeakSanitizer: detected memory leaks",
    "runtime error:",
    "[  FAILED  ]",
)
MAX_REPORT_BYTES = 512 << 20


def why_not_a_tracer_crash(output):
    """None when the output is a passed GoogleTest run ended by the tracer's crash, else why not."""
    if TRACER_CRASH not in output or "Tracer caught signal" not in output:
        return "no LeakSanitizer tracer crash in its output"
    for sign in REAL_FAILURE_SIGNS:
        if sign in output:
            return "its output reports '%s'" % sign
    if "[  PASSED  ]" not in output:
        return "its GoogleTest run did not report that its tests passed"
    return None


def main(argv):
    if len(argv) != 2:
        print(__doc__.strip().splitlines()[0], file=sys.stderr)
        print("usage: leak_checker_crashes.py JUNIT_XML", file=sys.stderr)
        return 2
    path = argv[1]
    try:
        with open(path, "rb") as report:
            data = report.read(MAX_REPORT_BYTES + 1)
        if len(data) > MAX_REPORT_BYTES:
            raise ValueError("larger than %d bytes" % MAX_REPORT_BYTES)
        root = ElementTree.fromstring(data)
    except (OSError, ValueError, ElementTree.ParseError) as error:
        print("leak_checker_crashes.py: %s: cannot read the report: %s" % (path, error), file=sys.stderr)
        return 2
    failed = [case for case in root.iter("testcase") if case.get("status") == "fail"]
    if not failed:
        print("leak_checker_crashes.py: %s: no failed test" % path)
        return 1
    all_crashes = True
    for case in failed:
        output = "".join(part.text or "" for part in case.iter("system-out"))
        reason = why_not_a_tracer_crash(output)
        if reason is None:
            print("  %s: passed, then LeakSanitizer's tracer crashed at exit" % case.get("name"))
        else:
            print("  %s: a real failure (%s)" % (case.get("name"), reason))
            all_crashes = False
    return 0 if all_crashes else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
