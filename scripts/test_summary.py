#!/usr/bin/env python3
"""Counts test cases in the JUnit XML files that catkin's run_tests leaves behind.

Prints every failed case with its message, then one closing line
"tests: N passed, N failed, N skipped"; exits 1 if any failed or if no test ran at all.
(catkin_test_results counts each gtest case twice, once for its suite and once for the file.)
A rostest leaves two files: rosunit-*.xml with the cases of its test node, and rostest-*.xml
with one wrapper case that fails only if the node crashed or left no results; the wrapper counts
only when it fails, so that a passing case is not counted twice.
"""
import pathlib
import sys
import xml.etree.ElementTree as ElementTree


def main(results_dir):
    passed, failed, skipped = 0, [], 0
    sanitized_passed, sanitized_failed = 0, 0  # of those, the sanitizer build's re-runs
    files = sorted(pathlib.Path(results_dir).rglob("*.xml"))
    for path in files:
        try:
            root = ElementTree.parse(path).getroot()
        except ElementTree.ParseError as error:
            failed.append(f"{path.name}: unreadable result file ({error})")
            continue
        for case in root.iter("testcase"):
            name = f"{case.get('classname', '')}.{case.get('name', '')}"
            problems = case.findall("failure") + case.findall("error")
            sanitized = path.parent.name == "sanitizers"
            if problems:
                message = (problems[0].get("message") or problems[0].text or "").strip()
                failed.append(f"{path.name}: {name}: {message.splitlines()[0] if message else ''}")
                sanitized_failed += 1 if sanitized else 0
            elif case.find("skipped") is not None or case.get("status") == "notrun":
                skipped += 1
            elif not path.name.startswith("rostest-"):
                passed += 1
                sanitized_passed += 1 if sanitized else 0
    for line in failed:
        print(f"FAILED {line}")
    if sanitized_passed or sanitized_failed:
        print(f"of these, unit tests again under ASan/LSan/UBSan: {sanitized_passed} passed, "
              f"{sanitized_failed} failed")
    print(f"tests: {passed} passed, {len(failed)} failed, {skipped} skipped")
    return 1 if failed or passed == 0 else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
