#!/usr/bin/env bash
# Runs every unit test of the sanitizer build (build/sanitize, see CMakeLists.txt), two at a time,
# with AddressSanitizer, LeakSanitizer and UndefinedBehaviorSanitizer set to stop at the first
# report. Each test leaves RESULTS/sanitize-<test>.xml (JUnit, read by scripts/test_summary.py);
# a test that a sanitizer stopped, or that crashed before writing its results, gets a file with
# one failed case quoting the report, so that `make test` fails and says why.
# With BUILD_LOG (`make test` builds the sanitizer build in the background, and BUILD_LOG.status
# holds its exit status), the build is a case of its own, RESULTS/build-sanitize.xml: failed
# with the log's first error and the log's end printed, as the programs that happen to exist
# would otherwise pass alone.
# usage: sanitizer_tests.sh TEST_BINARY_DIR RESULTS_DIR [BUILD_LOG]
set -euo pipefail
binaries=$1
results=$2
build_log=${3:-}
mkdir -p "$results"
export results
rm -f "$results"/sanitize-*.xml "$results"/build-sanitize.xml
export ASAN_OPTIONS=detect_leaks=1:halt_on_error=1:strict_string_checks=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1

# junit_case XML NAME [FAILURE]: one test case of the class "sanitizer", failed if FAILURE is
# given (XML's special characters in it become spaces).
junit_case() {
  local xml=$1 name=$2 failure=${3:-}
  local body="<testcase classname=\"sanitizer\" name=\"$name\"/>"
  if [ -n "$failure" ]; then
    body="<testcase classname=\"sanitizer\" name=\"$name\"><failure message=\"$(printf '%s' "$failure" | sed 's/[<>&"]/ /g')\"/></testcase>"
  fi
  printf '<?xml version="1.0"?>\n<testsuites><testsuite name="sanitizer" tests="1">\n%s\n</testsuite></testsuites>\n' \
    "$body" > "$xml"
}
export -f junit_case

if [ -n "$build_log" ]; then
  status=$(cat "$build_log.status" 2>/dev/null || echo "unknown")
  if [ "$status" = 0 ]; then
    junit_case "$results/build-sanitize.xml" build
  else
    echo "The sanitizer build failed (status $status); the end of $build_log:"
    tail -n 40 "$build_log" || true
    error=$({ grep -m1 -E "error|Error" "$build_log" || echo "status $status"; } | cut -c1-300)
    junit_case "$results/build-sanitize.xml" build \
      "the sanitizer build failed: $error (log: $build_log)"
  fi
fi

# run_one BINARY RESULTS [SHARD SHARDS]: one test program, or its SHARD-th of SHARDS parts
# (gtest's sharding: every SHARDS-th case from the SHARD-th).
run_one() {
  local binary=$1 results=$2 shard=${3:-} shards=${4:-}
  local name xml log status=0
  name=$(basename "$binary")
  if [ -n "$shards" ]; then
    name="$name-part$((shard + 1))of$shards"
    export GTEST_SHARD_INDEX=$shard GTEST_TOTAL_SHARDS=$shards
  fi
  xml="$results/sanitize-$name.xml"
  log="$results/sanitize-$name.log"
  "$binary" --gtest_output="xml:$xml" > "$log" 2>&1 || status=$?
  if [ "$status" -ne 0 ] && grep -qE "^(SUMMARY: [A-Za-z]+Sanitizer|==[0-9]+==ERROR)|runtime error:" "$log"; then
    # The sanitizer's report: its summary line, or the first runtime error.
    local report
    report=$(grep -m1 -E "^SUMMARY: [A-Za-z]+Sanitizer|runtime error:" "$log")
    junit_case "$xml" "$name" "$report (log: $log)"
  elif [ "$status" -ne 0 ] && [ ! -s "$xml" ]; then
    junit_case "$xml" "$name" "exited with status $status before writing results (log: $log)"
  fi
  echo "sanitizers: $name exit $status"
}
export -f run_one
# One case is left to the Release run: run_dataset_test's lower rates (72 s here, the longest)
# track the same MH01 frames with the same code three more times, at other rates; under the
# sanitizers the full-rate, quarter-rate and map cases run that code already.
export GTEST_FILTER="-RunDataset.Mh01SeenAtLowerRatesKeepsTheKeyframesOfAFullRateRun"
# The slowest first, so that the run does not end on one of them alone: run_dataset_test (110 s
# of the 230 s all take, two at a time) in three parts of about 50, 45 and 15 s, fab_map_test and
# map_file_test (35 s each); then the rest by name.
slowest="run_dataset_test fab_map_test map_file_test"
{
  if [ -x "$binaries/run_dataset_test" ]; then
    for shard in 0 1 2; do echo "$binaries/run_dataset_test $shard 3"; done
  fi
  for name in fab_map_test map_file_test; do
    if [ -x "$binaries/$name" ]; then echo "$binaries/$name"; fi
  done
  find "$binaries" -maxdepth 1 -name '*_test' -type f -executable | sort |
    { grep -v -x -F -f <(for name in $slowest; do echo "$binaries/$name"; done) || true; }
} | xargs -P 2 -L 1 bash -c 'run_one "$1" "$results" $2 $3' _
