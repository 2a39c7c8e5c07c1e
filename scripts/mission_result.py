#!/usr/bin/env python3
"""The exit code of a mission launch (roslaunch itself always exits 0): reads RUN_DIR/summary.json
and exits 0 when the mission ended DONE, 1 when it ended otherwise (FAILED, ABORTED) after at least
one scan, 2 for a start-up error: no summary written by this launch (--since: the launch's start,
seconds since the epoch; an older summary.json is a previous run's), or a mission that ended before
its first scan (a node that ended the launch at start-up, a driver that never came up). Prints one
line saying which.

  mission_result.py RUN_DIR [--since EPOCH]
"""
import argparse
import json
import os
import sys


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run_dir")
    ap.add_argument("--since", type=float, default=None, help="the launch's start [s since the epoch]")
    a = ap.parse_args()
    path = os.path.join(os.path.expanduser(a.run_dir), "summary.json")
    if not os.path.isfile(path):
        print("mission_result: no %s: the launch ended before the mission did (see the FATAL/ERROR lines above)" % path)
        return 2
    if a.since is not None and os.path.getmtime(path) < a.since - 1.0:
        print("mission_result: %s is from an earlier launch: this one ended before its mission did "
              "(see the FATAL/ERROR lines above)" % path)
        return 2
    try:
        s = json.load(open(path))
    except ValueError as e:
        print("mission_result: %s is not JSON (%s)" % (path, e))
        return 2
    state = s.get("state", "?")
    why = s.get("last_error") or s.get("complete_reason") or ""
    if state != "DONE" and not s.get("scans"):
        print("mission_result: world %s, mission %s before its first scan%s: a start-up error (see the FATAL/ERROR "
              "lines above)" % (s.get("world", "?"), state, (" (" + why + ")") if why else ""))
        return 2
    print("mission_result: world %s, mission %s%s" % (s.get("world", "?"), state, (": " + why) if why else ""))
    return 0 if state == "DONE" else 1


if __name__ == "__main__":
    sys.exit(main())
