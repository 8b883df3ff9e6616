// Linked into every executable of an AGEX_SANITIZE build (apps, tests, fuzzers): the
// sanitizer settings the suite runs with, so that a test fails on the first report and
// no one has to remember environment variables. ASAN_OPTIONS, LSAN_OPTIONS and
// UBSAN_OPTIONS given in the environment still take precedence.

extern "C" {
// detect_leaks: LeakSanitizer runs at exit; leaks fail the run.
// detect_stack_use_after_return: off, it costs time and memory in the long batch runs.
const char *
__asan_default_options ()
{
  return "detect_leaks=1:abort_on_error=0:halt_on_error=1:strict_string_checks=1:"
         "detect_stack_use_after_return=0:check_initialization_order=1";
}

const char *
__lsan_default_options ()
{
  return "suppressions=" AGEX_SANITIZER_DIR "/lsan.supp:print_suppressions=0";
}

const char *
__ubsan_default_options ()
{
  return "print_stacktrace=1:halt_on_error=1:suppressions=" AGEX_SANITIZER_DIR "/ubsan.supp";
}
}
