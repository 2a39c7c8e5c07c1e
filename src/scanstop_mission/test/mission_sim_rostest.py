#!/usr/bin/env python3
"""The scan-stop cycle end to end against sim_node, with crashes.

Starts icp_slam_node, explorer_node and mission_node (50 planes, a budget of 6 scans) on one run
directory, kills the SLAM node (SIGKILL) after the 2nd scan and restarts it, kills the mission node
after the 4th scan and restarts it, and checks that the mission ends DONE with exactly 6 scans,
each stored once in the map directory with the same pose the mission recorded, no collision, a
report, and a SLAM pose error well below odometry's.
"""
import json
import os
import sys

from scanstop_system import SystemTestCase, check_every_scan_once

PKG = "scanstop_mission"
BUDGET = 6


class MissionInSim(SystemTestCase):
    RUN_DIR_PREFIX = "scanstop_mission_rostest_"
    SYSTEM_ARGS = dict(planes=50, budget=BUDGET)  # sim_node comes from mission_sim.test

    def wait_for_scans(self, n, timeout):
        if not self.system.wait_for_scans(n, timeout):
            self.fail("fewer than %d scans after %d s (mission alive: %s); see %s/mission.out"
                      % (n, timeout, self.system.alive("mission"), self.run_dir))

    def test_mission_survives_crashes_and_keeps_every_scan(self):
        system = self.system
        system.start("slam")
        system.start("explorer")
        system.start("mission")
        self.wait_for_scans(2, 120)
        system.respawn("slam", delay=1.0)  # SLAM dies mid-run (between or during a registration); restarted, it reloads its map
        self.wait_for_scans(4, 150)
        system.respawn("mission", delay=0.0)  # resumes from mission_state.yaml
        if system.wait_mission(200) is None:
            self.fail("the mission did not end within 200 s; see %s" % self.run_dir)

        summary, scans = check_every_scan_once(self, self.run_dir, BUDGET)
        self.assertEqual(summary["collisions"], 0)
        # SLAM corrects what odometry gets wrong. 50 planes are sparse (6 cm between planes per metre
        # of range): 10-15 cm after 6 scans where odometry is 30-40 cm off, so loose bounds.
        self.assertTrue(summary["ground_truth"])
        self.assertLess(summary["final_slam_error_m"], 0.20, summary)
        self.assertLess(summary["final_slam_error_m"], 0.5 * summary["final_odometry_error_m"], summary)
        # The pose error of every scan (ATE) and the body's true clearance along the way are reported.
        # (scans SLAM registered while the mission was dead are adopted without a true pose)
        self.assertGreater(summary["ate_scans"], 0, summary)
        self.assertLessEqual(summary["ate_scans"], summary["scans"], summary)
        self.assertGreaterEqual(summary["ate_max_m"], summary["ate_rms_m"], summary)
        self.assertLess(summary["ate_max_m"], 0.50, summary)  # a sanity bound: 50 planes are sparse
        self.assertIsNotNone(summary["min_clearance_m"], summary)
        self.assertGreater(summary["legs_measured"], 0, summary)
        self.assertGreater(summary["min_clearance_m"], 0.0, summary)  # no collision: never touched
        for f in ("report.md", "report.html", "report_coverage.png", "report_trajectory.png", "report_pose_error.png",
                  "trajectory.csv", "mission.log", "explorer/floor_map.yaml"):
            self.assertTrue(os.path.exists(os.path.join(self.run_dir, f)), f)
        self.assertTrue(any(n.endswith(".png") for n in os.listdir(os.path.join(self.run_dir, "explorer"))))
        print("summary:", json.dumps(summary))


if __name__ == "__main__":
    import rostest
    rostest.rosrun(PKG, "mission_in_sim", MissionInSim, sys.argv)
