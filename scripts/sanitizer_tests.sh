#!/usr/bin/env bash
# Runs every unit test of the sanitizer build (build/sanitize, see CMakeLists.txt), two at a time,
# with AddressSanitizer, LeakSanitizer and UndefinedBehaviorSanitizer set to stop at the first
# report. Each test leaves RESULTS/sanitize-<test>.xml (JUnit, read by scripts/test_summary.py);
# a test that a sanitizer stopped, or that crashed before writing its results, gets a file with
# one failed case quoting the report, so that `make test` fails and says why.
# usage: sanitizer_tests.sh TEST_BINARY_DIR RESULTS_DIR
set -euo pipefail
binaries=$1
results=$2
mkdir -p "$results"
rm -f "$results"/sanitize-*.xml
export ASAN_OPTIONS=detect_leaks=1:halt_on_error=1:strict_string_checks=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1

run_one() {
  local binary=$1 results=$2
  local name xml log status=0
  name=$(basename "$binary")
  xml="$results/sanitize-$name.xml"
  log="$results/sanitize-$name.log"
  "$binary" --gtest_output="xml:$xml" > "$log" 2>&1 || status=$?
  if [ "$status" -ne 0 ] && grep -qE "^(SUMMARY: [A-Za-z]+Sanitizer|==[0-9]+==ERROR)|runtime error:" "$log"; then
    # The sanitizer's report: its summary line, or the first runtime error.
    local report
    report=$(grep -m1 -E "^SUMMARY: [A-Za-z]+Sanitizer|runtime error:" "$log" | sed 's/[<>&"]/ /g')
    printf '<?xml version="1.0"?>\n<testsuites><testsuite name="sanitizer" tests="1">\n<testcase classname="sanitizer" name="%s"><failure message="%s (log: %s)"/></testcase>\n</testsuite></testsuites>\n' \
      "$name" "$report" "$log" > "$xml"
  elif [ "$status" -ne 0 ] && [ ! -s "$xml" ]; then
    printf '<?xml version="1.0"?>\n<testsuites><testsuite name="sanitizer" tests="1">\n<testcase classname="sanitizer" name="%s"><failure message="exited with status %s before writing results (log: %s)"/></testcase>\n</testsuite></testsuites>\n' \
      "$name" "$status" "$log" > "$xml"
  fi
  echo "sanitizers: $name exit $status"
}
export -f run_one
# The slowest first (run_dataset_test 81 s, map_file_test 31 s of the 135 s all take, two at a
# time), so that the run does not end on one of them alone; then the rest by name.
slowest="run_dataset_test map_file_test"
{
  for name in $slowest; do
    if [ -x "$binaries/$name" ]; then echo "$binaries/$name"; fi
  done
  find "$binaries" -maxdepth 1 -name '*_test' -type f -executable | sort |
    { grep -v -x -F -f <(for name in $slowest; do echo "$binaries/$name"; done) || true; }
} | xargs -P 2 -I{} bash -c 'run_one "$@"' _ {} "$results"
