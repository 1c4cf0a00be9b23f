#!/usr/bin/env python3
"""Counts test cases in the JUnit XML files that catkin's run_tests leaves behind.

usage: test_summary.py RESULTS_DIR [--expected FILE]

Prints every failed case with its message, then the closing lines
"tests: N passed, N failed, N skipped" (the distinct cases of the release build) and, if the
sanitizer build ran, "sanitizer build: ..." (its build and its re-runs of the unit tests under
ASan/LSan/UBSan, counted apart: they are the same cases again). Exits 1 if any case failed, if
no test ran at all, or if a result file listed in FILE (written by CMake: one per test program
and rostest) is missing, as it is when a test program was killed or never run.
(catkin_test_results counts each gtest case twice, once for its suite and once for the file.)
A rostest leaves two files: rosunit-*.xml with the cases of its test node, and rostest-*.xml
with one wrapper case that fails only if the node crashed or left no results; the wrapper counts
only when it fails, so that a passing case is not counted twice.
"""
import argparse
import pathlib
import sys
import xml.etree.ElementTree as ElementTree


def main(results_dir, expected_file):
    passed, failed, skipped = 0, [], 0
    sanitized_passed, sanitized_failed = 0, 0  # the sanitizer build's cases, not in `passed`
    files = sorted(pathlib.Path(results_dir).rglob("*.xml"))
    for path in files:
        sanitized = path.parent.name == "sanitizers"
        try:
            root = ElementTree.parse(path).getroot()
        except ElementTree.ParseError as error:
            failed.append(f"{path.name}: unreadable result file ({error})")
            sanitized_failed += 1 if sanitized else 0
            continue
        for case in root.iter("testcase"):
            name = f"{case.get('classname', '')}.{case.get('name', '')}"
            problems = case.findall("failure") + case.findall("error")
            if problems:
                message = (problems[0].get("message") or problems[0].text or "").strip()
                failed.append(f"{path.name}: {name}: {message.splitlines()[0] if message else ''}")
                sanitized_failed += 1 if sanitized else 0
            elif case.find("skipped") is not None or case.get("status") == "notrun":
                skipped += 1
            elif sanitized:
                sanitized_passed += 1
            elif not path.name.startswith("rostest-"):
                passed += 1
    if expected_file:
        found = {path.name for path in files if path.parent.name != "sanitizers"}
        for name in pathlib.Path(expected_file).read_text().split():
            if name not in found:
                failed.append(f"{name}: no result file (the test program was killed, or never "
                              "run, before it wrote its results)")
    for line in failed:
        print(f"FAILED {line}")
    if sanitized_passed or sanitized_failed:
        print(f"sanitizer build: its build and the unit tests again under ASan/LSan/UBSan, "
              f"{sanitized_passed} passed, {sanitized_failed} failed")
    distinct_failed = len(failed) - sanitized_failed
    print(f"tests: {passed} passed, {distinct_failed} failed, {skipped} skipped")
    return 1 if failed or passed == 0 else 0


if __name__ == "__main__":
    arguments = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    arguments.add_argument("results_dir")
    arguments.add_argument("--expected", help="the result files that must exist, one a line")
    options = arguments.parse_args()
    sys.exit(main(options.results_dir, options.expected))
