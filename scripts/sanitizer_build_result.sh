#!/usr/bin/env bash
# After `make test` built the sanitizer build in the background: prints the end of its log if it
# failed, and leaves RESULTS/build-sanitize.xml with one test case, failed with the log's last
# error line, so that scripts/test_summary.py counts the failure (sanitizer_tests.sh would only
# run the test programs that happen to exist).
# usage: sanitizer_build_result.sh BUILD_LOG RESULTS_DIR
set -euo pipefail
log=$1
results=$2
mkdir -p "$results"
status=$(cat "$log.status" 2>/dev/null || echo "no status")
if [ "$status" = 0 ]; then
  printf '<?xml version="1.0"?>\n<testsuites><testsuite name="sanitizer" tests="1">\n<testcase classname="sanitizer" name="build"/>\n</testsuite></testsuites>\n' \
    > "$results/build-sanitize.xml"
  exit 0
fi
echo "The sanitizer build failed (status $status); the end of $log:"
tail -n 40 "$log" || true
error=$({ grep -m1 -E "error|Error" "$log" || echo "status $status"; } | sed 's/[<>&"]/ /g' | cut -c1-300)
printf '<?xml version="1.0"?>\n<testsuites><testsuite name="sanitizer" tests="1">\n<testcase classname="sanitizer" name="build"><failure message="the sanitizer build failed: %s (log: %s)"/></testcase>\n</testsuite></testsuites>\n' \
  "$error" "$log" > "$results/build-sanitize.xml"
