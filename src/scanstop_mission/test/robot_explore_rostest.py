#!/usr/bin/env python3
"""launch/robot_explore.launch on the device emulators: the mission runs scan-stop cycles through
pioneer_driver and rotating_urg_driver (real serial protocols on pseudo-terminals) and ends DONE
with its scans registered, motions driven by odometry, and its report written."""
import csv
import json
import os
import sys
import time
import unittest

import rospy
from scanstop_msgs.msg import MissionStatus

PKG = "scanstop_mission"


class RobotExploreOnEmulators(unittest.TestCase):
    def test_mission_runs_on_the_drivers(self):
        rospy.init_node("robot_explore_rostest")
        run_dir = rospy.get_param("~run_dir")
        last = {}

        def on_status(msg):
            last["msg"] = msg

        rospy.Subscriber("mission/status", MissionStatus, on_status)
        deadline = time.time() + 200
        while time.time() < deadline and not rospy.is_shutdown():
            msg = last.get("msg")
            if msg is not None and msg.state in ("DONE", "FAILED", "ABORTED"):
                break
            time.sleep(0.5)
        msg = last.get("msg")
        self.assertIsNotNone(msg, "no mission/status message")
        self.assertEqual(msg.state, "DONE", "mission ended %s: %s" % (msg.state, msg.last_error))
        # The mission writes summary.json, then the plots and report.md (seconds on a loaded machine).
        deadline = time.time() + 60
        summary_path = os.path.join(run_dir, "summary.json")
        report_path = os.path.join(run_dir, "report.md")
        while not (os.path.exists(summary_path) and os.path.exists(report_path)) and time.time() < deadline:
            time.sleep(0.2)
        with open(summary_path) as f:
            summary = json.load(f)
        self.assertEqual(summary["collisions"], 0)
        self.assertGreaterEqual(summary["scans"], 2, summary)  # at least one cycle: scan, drive, scan
        self.assertFalse(summary["ground_truth"])
        with open(os.path.join(run_dir, "map", "poses.csv")) as f:
            rows = list(csv.DictReader(f))
        self.assertEqual(len(rows), summary["scans"])
        # The robot moved between the scans: odometry from pioneer_driver saw the motion.
        moved = max(abs(float(r["odom_x"])) + abs(float(r["odom_y"])) for r in rows)
        self.assertGreater(moved, 0.2, rows)
        self.assertTrue(os.path.exists(report_path), "no report.md 60 s after the summary")


if __name__ == "__main__":
    import rostest
    rostest.rosrun(PKG, "robot_explore_on_emulators", RobotExploreOnEmulators, sys.argv)
