#!/usr/bin/env python3
"""The scan-stop cycle end to end against sim_node, with crashes.

Starts icp_slam_node, explorer_node and mission_node (50 planes, a budget of 6 scans) on one run
directory, kills the SLAM node (SIGKILL) after the 2nd scan and restarts it, kills the mission node
after the 4th scan and restarts it, and checks that the mission ends DONE with exactly 6 scans,
each stored once in the map directory with the same pose the mission recorded, no collision, a
report, and a SLAM pose error well below odometry's.
"""
import csv
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import unittest

import yaml

PKG = "scanstop_mission"
BUDGET = 6


def mission_scans(run_dir):
    try:
        with open(os.path.join(run_dir, "mission_state.yaml")) as f:
            state = yaml.safe_load(f) or {}
        return state.get("scans") or []
    except (OSError, yaml.YAMLError):
        return []


class MissionInSim(unittest.TestCase):
    def setUp(self):
        self.run_dir = tempfile.mkdtemp(prefix="scanstop_mission_rostest_")
        self.procs = {}

    def tearDown(self):
        for p in self.procs.values():
            if p.poll() is None:
                p.kill()
                p.wait()
        if os.environ.get("MISSION_KEEP_RUN_DIR"):
            print("run directory kept:", self.run_dir)
        else:
            shutil.rmtree(self.run_dir, ignore_errors=True)

    def start(self, name):
        run = self.run_dir
        args = {
            "slam": ["rosrun", "scanstop_slam", "icp_slam_node", "__name:=icp_slam_node", "_map_dir:=%s/map" % run],
            "explorer": ["rosrun", "scanstop_explorer", "explorer_node", "__name:=explorer_node",
                         "_map_dir:=%s/map" % run, "_run_dir:=%s/explorer" % run, "_k_r_m:=2.5"],
            "mission": ["rosrun", PKG, "mission_node", "__name:=mission_node", "_run_dir:=%s" % run,
                        "_map_dir:=%s/map" % run, "_planes:=50", "_max_scans:=%d" % BUDGET, "_world:=room_10x8",
                        "_shutdown_when_done:=true", "_wait_for_service_timeout:=60.0"],
        }[name]
        log = open(os.path.join(run, "%s.out" % name), "a")
        self.procs[name] = subprocess.Popen(args, stdout=log, stderr=subprocess.STDOUT)

    def kill(self, name):
        p = self.procs[name]
        p.send_signal(signal.SIGKILL)
        p.wait()

    def wait_for_scans(self, n, timeout):
        deadline = time.time() + timeout
        while time.time() < deadline:
            if len(mission_scans(self.run_dir)) >= n:
                return
            if self.procs["mission"].poll() is not None:
                self.fail("mission_node ended early (exit %s); see %s/mission.out"
                          % (self.procs["mission"].returncode, self.run_dir))
            time.sleep(0.2)
        self.fail("fewer than %d scans after %d s; see %s" % (n, timeout, self.run_dir))

    def test_mission_survives_crashes_and_keeps_every_scan(self):
        self.start("slam")
        self.start("explorer")
        self.start("mission")
        self.wait_for_scans(2, 120)
        self.kill("slam")   # SLAM dies mid-run (between or during a registration) ...
        time.sleep(1.0)
        self.start("slam")  # ... and is restarted (respawn): it reloads its map directory
        self.wait_for_scans(4, 150)
        self.kill("mission")
        self.start("mission")  # resumes from mission_state.yaml
        try:
            self.procs["mission"].wait(timeout=200)
        except subprocess.TimeoutExpired:
            self.fail("the mission did not end within 200 s; see %s" % self.run_dir)

        with open(os.path.join(self.run_dir, "summary.json")) as f:
            summary = json.load(f)
        self.assertEqual(summary["state"], "DONE", summary)
        self.assertEqual(summary["scans"], BUDGET, summary)
        self.assertEqual(summary["collisions"], 0)
        scans = mission_scans(self.run_dir)
        self.assertEqual([s["index"] for s in scans], list(range(BUDGET)))
        with open(os.path.join(self.run_dir, "map", "poses.csv")) as f:
            rows = list(csv.DictReader(f))
        self.assertEqual([int(r["index"]) for r in rows], list(range(BUDGET)), "each scan stored once")
        for s, r in zip(scans, rows):
            self.assertAlmostEqual(s["map_pose"][0], float(r["map_x"]), places=6)
            self.assertAlmostEqual(s["map_pose"][1], float(r["map_y"]), places=6)
            self.assertTrue(os.path.exists(os.path.join(self.run_dir, "map", r["file"])))
        # SLAM corrects what odometry gets wrong (50 planes: a loose bound).
        self.assertTrue(summary["ground_truth"])
        self.assertLess(summary["final_slam_error_m"], 0.10, summary)
        for f in ("report.md", "coverage.png", "trajectory.png", "mission.log"):
            self.assertTrue(os.path.exists(os.path.join(self.run_dir, f)), f)
        self.assertTrue(any(n.endswith(".png") for n in os.listdir(os.path.join(self.run_dir, "explorer"))))
        print("summary:", json.dumps(summary))


if __name__ == "__main__":
    import rostest
    rostest.rosrun(PKG, "mission_in_sim", MissionInSim, sys.argv)
