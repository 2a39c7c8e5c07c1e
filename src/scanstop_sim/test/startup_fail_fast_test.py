#!/usr/bin/env python3
"""sim_node started by roslaunch with respawn="true" (as launch/sim_explore.launch starts it) and a
start-up error must end the launch within 15 s, the FATAL naming the right cause: the world file
when it is missing (not start_pose), the floor, the start pose when it is garbage or in a wall.
Before issue 22 sim_node respawned ~160 times and the launch ran on. Run by startup_fail_fast.test
(the rostest's master serves the inner roslaunch)."""
import os
import shutil
import subprocess
import sys
import tempfile
import time
import unittest

import rospkg
import rostest

PKG = "scanstop_sim"
ROOT = os.path.normpath(os.path.join(rospkg.RosPack().get_path(PKG), "..", ".."))
ROOM = os.path.join(ROOT, "worlds", "room_10x8.stl")

LAUNCH = """<launch>
  <node pkg="scanstop_sim" type="sim_node" name="ff_sim_node" output="log" respawn="true" respawn_delay="1.0">
    <param name="world" value="%(world)s"/>
    <param name="start_pose" value="%(start)s"/>
    <param name="state_file" value="%(dir)s/run/sim_state.txt"/>
    <param name="end_launch_on_setup_error" value="true"/>
  </node>
</launch>
"""


class StartupFailFast(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="scanstop_sim_ff_")

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def launch(self, name, world, start, *expected, absent=()):
        path = os.path.join(self.tmp, name + ".launch")
        with open(path, "w") as f:
            f.write(LAUNCH % {"world": world, "start": start, "dir": self.tmp})
        env = dict(os.environ, ROS_LOG_DIR=os.path.join(self.tmp, "log_" + name))
        t0 = time.time()
        proc = subprocess.Popen(["roslaunch", "--skip-log-check", path], stdout=subprocess.PIPE,
                                stderr=subprocess.STDOUT, universal_newlines=True, env=env)
        try:
            out, _ = proc.communicate(timeout=15)
        except subprocess.TimeoutExpired:
            proc.send_signal(2)
            out, _ = proc.communicate(timeout=30)
            self.fail("%s: the launch still ran after 15 s (respawn loop):\n%s" % (name, out[-3000:]))
        took = time.time() - t0
        fatal = [l for l in out.splitlines() if "FATAL" in l and "ending the launch" not in l]
        self.assertTrue(fatal, "%s: no FATAL line on the launch's screen:\n%s" % (name, out))
        self.assertLessEqual(len(fatal), 2, "%s: sim_node respawned:\n%s" % (name, out))
        for e in expected:
            self.assertIn(e, fatal[0], "%s: the FATAL lacks %r:\n%s" % (name, e, out))
        for a in absent:
            self.assertNotIn(a, fatal[0], "%s: the FATAL wrongly names %r:\n%s" % (name, a, out))
        print("%s: launch ended after %.1f s: %s" % (name, took, fatal[0]))

    def test_missing_world_file(self):
        missing = os.path.join(self.tmp, "corridr.stl")
        self.launch("missing", missing, "", "ff_sim_node/world'", missing, "the world file does not exist",
                    absent=("start_pose",))

    def test_world_without_floor(self):
        wall = os.path.join(self.tmp, "wall.stl")
        with open(wall, "w") as f:
            f.write("solid wall\n facet normal 0 1 0\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n"
                    "   vertex 0 0 1\n  endloop\n endfacet\nendsolid wall\n")
        self.launch("no_floor", wall, "0,0,0", "the world has no floor")

    def test_garbage_start_pose(self):
        self.launch("garbage", ROOM, "a,b,c", "start_pose' = 'a,b,c'", "not a number")

    def test_start_pose_in_a_wall(self):
        self.launch("in_wall", ROOM, "0.0,4.0,0.0", "start_pose' = '0.0,4.0,0.0'", "into an obstacle")


if __name__ == "__main__":
    rostest.rosrun(PKG, "sim_startup_fail_fast", StartupFailFast, sys.argv)
