#!/usr/bin/python3
"""Counts the JUnit XML results under a directory and prints `tests: N passed, M failed`.

Every <testcase> is one test; it failed when it holds a <failure> or <error> (its first lines
are printed under the FAILED line). A results file
that is missing (catkin writes MISSING-*.xml for it) or unreadable counts as one failed test.
Exit status: 0 when nothing failed and at least one test ran, 1 otherwise.
"""
import glob
import os
import sys
import xml.etree.ElementTree as ET


def excerpt(element, max_lines=25):
    """The first lines of a <failure>/<error> (message and text), indented, so a CI log shows why."""
    text = "\n".join(t for t in (element.get("message", ""), element.text or "") if t.strip())
    lines = [l for l in text.splitlines() if l.strip()]
    if not lines:
        return ""
    more = ["... (%d more lines in the XML)" % (len(lines) - max_lines)] if len(lines) > max_lines else []
    return "".join("\n    | " + l[:300] for l in lines[:max_lines] + more)


def count(path):
    """Returns (passed, failed, skipped, failed_names) for one JUnit file."""
    name = os.path.relpath(path)
    try:
        root = ET.parse(path).getroot()
    except (ET.ParseError, OSError) as e:
        return 0, 1, 0, ["%s (unreadable: %s)" % (name, e)]
    passed = failed = skipped = 0
    failed_names = []
    cases = root.iter("testcase")
    seen = False
    for case in cases:
        seen = True
        label = "%s.%s" % (case.get("classname", ""), case.get("name", ""))
        bad = case.find("failure")
        if bad is None:
            bad = case.find("error")
        if bad is not None:
            failed += 1
            failed_names.append("%s: %s%s" % (name, label, excerpt(bad)))
        elif case.find("skipped") is not None or case.get("status") == "notrun":
            skipped += 1
        else:
            passed += 1
    if not seen:
        # A suite without test cases: trust its counters (rostest writes them), else it is a failure.
        tests = int(root.get("tests", "0") or 0)
        bad = int(root.get("failures", "0") or 0) + int(root.get("errors", "0") or 0)
        if tests == 0 and bad == 0:
            return 0, 1, 0, ["%s (no test cases)" % name]
        return max(tests - bad, 0), bad, 0, (["%s" % name] if bad else [])
    return passed, failed, skipped, failed_names


def main():
    results_dir = sys.argv[1] if len(sys.argv) > 1 else "build/test_results"
    files = sorted(glob.glob(os.path.join(results_dir, "**", "*.xml"), recursive=True))
    passed = failed = skipped = 0
    failures = []
    for path in files:
        p, f, s, names = count(path)
        passed, failed, skipped = passed + p, failed + f, skipped + s
        failures += names
    for line in failures:
        print("FAILED: " + line)
    suffix = ", %d skipped" % skipped if skipped else ""
    if not files:
        failed += 1
        print("FAILED: no test results found in %s" % results_dir)
    print("tests: %d passed, %d failed%s" % (passed, failed, suffix))
    return 0 if failed == 0 and passed > 0 else 1


if __name__ == "__main__":
    sys.exit(main())
