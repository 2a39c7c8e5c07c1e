#!/usr/bin/python3
"""roslaunch-check for launch files outside a package (the workspace's launch/ folder).

Usage: check_launch.py OUTPUT_DIR FILE.launch [...]
For each file, runs roslaunch's own check (XML, args, that every package and node executable exists)
and writes one JUnit file OUTPUT_DIR/<name>.xml with one test case. Exit 1 if any check failed.
An arg declared without a default (a required argument, such as replay.launch's `bag`) is given a
placeholder value for the check, the way a user gives it on the command line.
"""
import os
import sys
import xml.etree.ElementTree as ET
from xml.sax.saxutils import escape, quoteattr

import roslaunch.rlutil


def required_args(path):
    """Top-level <arg> declarations without default or value."""
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError:
        return []  # roslaunch's check reports the XML error
    return [a.get("name") for a in root.findall("arg")
            if a.get("name") and a.get("default") is None and a.get("value") is None]


def main():
    out_dir, files = sys.argv[1], sys.argv[2:]
    argv0 = sys.argv[0]
    os.makedirs(out_dir, exist_ok=True)
    failed = 0
    for path in files:
        name = path.replace(os.sep, "_").replace(".", "_")
        try:
            required = required_args(path)
            # roslaunch's loader reads name:=value mappings from sys.argv.
            sys.argv = [argv0] + ["%s:=check_placeholder" % a for a in required]
            error = roslaunch.rlutil.check_roslaunch(path)
        except Exception as e:  # the check itself crashed: that is a failure of the file
            error = "check crashed: %s" % e
        status = "ok" if not error else "FAILED: %s" % error
        print("launch check %s: %s" % (path, status))
        body = "" if not error else '<failure message=%s>%s</failure>' % (quoteattr("launch check failed"), escape(error))
        with open(os.path.join(out_dir, name + ".xml"), "w") as f:
            f.write('<?xml version="1.0" encoding="UTF-8"?>\n'
                    '<testsuite name="launch_check" tests="1" failures="%d" errors="0">\n'
                    '  <testcase classname="launch_check" name=%s>%s</testcase>\n</testsuite>\n'
                    % (1 if error else 0, quoteattr(path), body))
        failed += 1 if error else 0
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
