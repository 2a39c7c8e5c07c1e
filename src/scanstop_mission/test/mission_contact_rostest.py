#!/usr/bin/env python3
"""A forced contact: the robot backs off and never touches that spot again (issue #18).

The test starts sim_node (room_10x8, thesis errors, seed 3), arms a hidden obstacle (a
cylinder of radius 0.1 m the laser does not see) 0.7 m into the way of the robot's first straight leg
that reaches it (ahead, or behind on a backward leg), then runs icp_slam_node, explorer_node and mission_node (50 planes, 6 scans).
The mission must end DONE with exactly one collision (the forced one), the contact recorded in its
state, the back-off as the next motion in its log, and every later leg clear of the cylinder (the
true clearance of each motion comes from sim_node; a second touch would be a second collision).
"""
import json
import math
import os
import re
import sys

import rospy
import yaml
from scanstop_msgs.srv import AddHiddenObstacle

from scanstop_system import SystemTestCase, check_every_scan_once

PKG = "scanstop_mission"
BUDGET = 6
AHEAD_M, RADIUS_M = 0.7, 0.1


class MissionContact(SystemTestCase):
    RUN_DIR_PREFIX = "scanstop_contact_rostest_"
    SYSTEM_ARGS = dict(planes=50, budget=BUDGET, world="room_10x8", seed=3)

    def test_back_off_and_never_touch_the_spot_again(self):
        self.system.start("sim")
        rospy.wait_for_service("sim/add_hidden_obstacle", 60)
        add = rospy.ServiceProxy("sim/add_hidden_obstacle", AddHiddenObstacle)
        # bad requests are refused with a reason and change nothing
        bad = add(frame_id="map", x=0.0, y=0.0, radius=0.1, on_next_forward=False)  # on the robot
        self.assertFalse(bad.success)
        self.assertIn("would touch the robot", bad.message)
        bad = add(frame_id="odom", x=3.0, y=0.0, radius=0.1, on_next_forward=False)
        self.assertFalse(bad.success)
        self.assertIn("odom", bad.message)
        armed = add(x=AHEAD_M, y=0.0, radius=RADIUS_M, on_next_forward=True)
        self.assertTrue(armed.success, armed.message)

        system = self.system
        system.start("slam")
        system.start("explorer")
        system.start("mission")
        if system.wait_mission(360) is None:
            self.fail("the mission did not end within 360 s; see %s" % self.run_dir)
        summary, _ = check_every_scan_once(self, self.run_dir, BUDGET)
        print("summary:", json.dumps(summary))
        self.assertEqual(summary["collisions"], 1, summary)  # the forced one, and never again
        with open(os.path.join(self.run_dir, "mission_state.yaml")) as f:
            state = yaml.safe_load(f)
        self.assertEqual(len(state.get("contacts") or []), 1, state.get("contacts"))
        with open(os.path.join(self.run_dir, "mission.log")) as f:
            log = f.read().splitlines()
        contact = [i for i, line in enumerate(log) if re.search(r"contact 1 of at most \d+ at", line)]
        self.assertEqual(len(contact), 1, "\n".join(log))
        # the next motion is the back-off (near-miss lines are ground-truth figures, not motions)
        after = [line for line in log[contact[0] + 1:] if "near miss (ground truth)" not in line]
        self.assertTrue(after, "\n".join(log))
        self.assertRegex(after[0], r"backed off by 0\.\d+ m after the contact", "\n".join(log))
        # the recorded contact lies at the hidden cylinder (map frame: sim_node's start pose is the map origin)
        hidden = [line.split()[1:] for line in open(os.path.join(self.run_dir, "sim_state.txt"))
                  if line.startswith("hidden_obstacle")]
        self.assertEqual(len(hidden), 1, hidden)
        start = [line.split()[1:] for line in open(os.path.join(self.run_dir, "sim_state.txt"))
                 if line.startswith("start")][0]
        hx, hy = float(hidden[0][0]), float(hidden[0][1])
        sx, sy, syaw = (float(v) for v in start)
        mx = math.cos(-syaw) * (hx - sx) - math.sin(-syaw) * (hy - sy)
        my = math.sin(-syaw) * (hx - sx) + math.cos(-syaw) * (hy - sy)
        cx, cy, radius = state["contacts"][0]
        self.assertTrue(0.0 <= radius <= 2.0, state["contacts"])  # 0: the explorer's contact_radius_m
        self.assertLess(math.hypot(cx - mx, cy - my), 0.3, (state["contacts"], (mx, my)))
        # after the contact every motion kept clear: the smallest true clearance of the run is the contact's 0
        # and there was no second one; the legs measured go on after it
        self.assertGreater(summary["legs_measured"], 2, summary)


if __name__ == "__main__":
    rospy.init_node("mission_contact_rostest")
    import rostest
    rostest.rosrun(PKG, "mission_contact", MissionContact, sys.argv)
