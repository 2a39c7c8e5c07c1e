#!/usr/bin/env python3
"""A short mission in a furnished flat ends without touching anything (issue #18).

Starts icp_slam_node, explorer_node and mission_node (50 planes, a budget of 8 scans) against the
sim_node of mission_furnished.test (worlds/furnished_1.stl: furniture with overhangs, thin legs and
low boards), and checks that the mission ends DONE with no collision, that the true clearance of
the body along every driven leg is measured and reported (summary.json's min_clearance_m,
legs_measured) and stays above zero.
"""
import json
import sys

from scanstop_system import SystemTestCase, check_every_scan_once

PKG = "scanstop_mission"
BUDGET = 8


class MissionFurnished(SystemTestCase):
    RUN_DIR_PREFIX = "scanstop_furnished_rostest_"
    SYSTEM_ARGS = dict(planes=50, budget=BUDGET, world="furnished_1")

    def test_no_contact_and_clearance_reported(self):
        system = self.system
        system.start("slam")
        system.start("explorer")
        system.start("mission")
        if system.wait_mission(360) is None:
            self.fail("the mission did not end within 360 s; see %s" % self.run_dir)
        summary, _ = check_every_scan_once(self, self.run_dir, BUDGET)
        print("summary:", json.dumps(summary))
        self.assertEqual(summary["collisions"], 0, summary)
        self.assertIsNotNone(summary["min_clearance_m"], summary)
        self.assertGreater(summary["legs_measured"], 0, summary)
        self.assertGreater(summary["min_clearance_m"], 0.0, summary)


if __name__ == "__main__":
    import rostest
    rostest.rosrun(PKG, "mission_furnished", MissionFurnished, sys.argv)
