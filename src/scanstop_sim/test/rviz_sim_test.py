#!/usr/bin/python3
"""rviz/sim.rviz headless, checked for what a user must see. sim_node runs room_10x8 with the robot
at its start (2, 5). rviz runs under xvfb-run (full screen) with sim.rviz's displays, seen from
straight above (the one change: a top-down view of known scale, so that a world point has a known
pixel). A first screenshot must show
  - the room's floor (the world mesh over the background; no ceiling hides it: sim_node leaves it out
    of sim/world_mesh, world_display_max_z_m), and outside the world the background;
  - the walls along their lines (the north, west and south walls);
  - the robot, drawn from its URDF (the red body of config/robot_body.yaml), where it stands.
Then the test takes a scan and turns the robot by 0.5 rad (the latched scan's stamp lies before the
current pose); a second screenshot must show the scan's floor points (rviz's rainbow by height:
magenta at the floor) around the robot out to about the scanner's range, and none beyond it.
rviz must log no errors. (rviz draws point clouds over opaque shapes here: after a scan the points
under the robot hide it, which is why the robot is checked before the scan.)"""
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import unittest

import rospkg
import rospy
import rostest
from scanstop_msgs.srv import Rotate, TakeScan

sys.path.insert(0, os.path.join(rospkg.RosPack().get_path("scanstop_common"), "scripts"))
import rviz_screenshot  # noqa: E402
from rviz_screenshot import Screen, grey  # noqa: E402

# rviz lines that are not display errors (Debian's rviz asks rospack for an optional package).
BENIGN = [re.compile(p) for p in (r"no such package media_export", r"\[librospack\]: error while executing command")]

BACKGROUND = (48, 48, 48)      # sim.rviz's Background Color
SCALE = 60.0                   # pixels per metre of the top-down view
FOCUS = (5.0, 3.0)             # world point at the centre of the render panel
START = (2.0, 5.0)             # room_10x8's start pose (world frame), heading 0
TURN = 0.5                     # [rad] the turn after the scan


def is_background(c):
    return grey(c, BACKGROUND[0] - 4, BACKGROUND[0] + 4)


def is_floor(c):
    """The world mesh (grey 0.7 at alpha 0.35) over the background, one layer: a ceiling over it
    would add a second."""
    return grey(c, 80, 106)


def is_wall(c):
    """A wall from above: the dark gap between its two faces, drawn edge-on."""
    return grey(c, BACKGROUND[0] + 4, 78)


def is_robot_red(c):
    """The URDF's body (0.75, 0.1, 0.1), lit from above."""
    return c[0] >= 90 and c[0] >= 2 * c[1] and c[0] >= 2 * c[2]


def is_floor_point(c):
    """A scan point at floor height: the low end of rviz's rainbow, magenta."""
    return c[0] >= 150 and c[2] >= 150 and c[1] <= 80


class RvizSim(unittest.TestCase):
    def test_rviz_shows_room_robot_and_scan(self):
        config = rospy.get_param("~rviz_config")
        rospy.wait_for_service("scanner/take_scan", 60)
        work = tempfile.mkdtemp(prefix="rviz_sim_")
        keep = os.environ.get("RVIZ_SIM_KEEP")  # a directory: the screenshots (PNG) and rviz's log go there
        try:
            view_config = os.path.join(work, "sim_top_down.rviz")
            with open(config) as f, open(view_config, "w") as out:
                out.write(rviz_screenshot.top_down_config(f.read(), SCALE, FOCUS))
            shots = [os.path.join(work, "before_scan.xwd"), os.path.join(work, "after_scan.xwd")]
            go = os.path.join(work, "scanned")
            log = os.path.join(work, "rviz.log")
            # Screenshot 1 after 20 s (a loaded machine renders slowly), then wait for the scan, and
            # screenshot 2 15 s after it.
            script = ('%s & R=$!; sleep 20; xwd -root -silent > "%s"; '
                      'for i in $(seq 600); do [ -e "%s" ] && break; sleep 0.2; done; sleep 15; '
                      'xwd -root -silent > "%s"; kill $R; wait $R; true' %
                      (rviz_screenshot.rviz_command(view_config, log), shots[0], go, shots[1]))
            rviz = subprocess.Popen(["xvfb-run", "-a", "-s", "-screen 0 1400x900x24", "bash", "-c", script])
            try:
                deadline = time.time() + 90  # wall time: the simulated clock stands while nothing moves
                while not os.path.exists(shots[0]) and rviz.poll() is None:
                    time.sleep(0.5)
                    self.assertLess(time.time(), deadline, "no first screenshot")
                time.sleep(2.0)  # xwd has finished writing it
                scan = rospy.ServiceProxy("scanner/take_scan", TakeScan)(planes=200)
                self.assertTrue(scan.success, scan.message)
                turn = rospy.ServiceProxy("base/rotate", Rotate)(angle_rad=TURN)
                self.assertTrue(turn.success, turn.message)
                open(go, "w").close()
                self.assertEqual(rviz.wait(timeout=120), 0)
            finally:
                if rviz.poll() is None:
                    rviz.kill()
            with open(log) as f:
                lines = f.read().splitlines()
            screens = [Screen(shot, SCALE, FOCUS) for shot in shots]
            pngs = []
            for shot, screen in zip(shots, screens):
                png = os.path.join(keep or work, os.path.basename(shot).replace(".xwd", ".png"))
                screen.write_png(png)
                pngs.append(png)
            if keep:
                shutil.copy(log, os.path.join(keep, "rviz.log"))
            self.assertTrue(any("rviz version" in line for line in lines), "rviz did not start:\n" + "\n".join(lines))
            errors = [line for line in lines
                      if re.search(r"ERROR|FATAL|[Ff]ailed|[Ee]rror", line) and not any(b.search(line) for b in BENIGN)]
            self.assertEqual(errors, [], "rviz logged errors:\n" + "\n".join(errors))
            self.check_room_and_robot(screens[0], " (screenshot %s)" % pngs[0])
            self.check_scan(screens[1], " (screenshot %s)" % pngs[1])
        finally:
            shutil.rmtree(work, ignore_errors=True)

    def check_room_and_robot(self, s, where):
        self.assertEqual((s.width, s.height), (1400, 900))
        # Outside the world (between the grid's lines): the background.
        for p in [(11.5, 3.5), (-1.5, 3.5), (5.5, 9.5)]:
            self.assertTrue(is_background(s.at(*p)), "%s is not background: %s%s" % (p, s.at(*p), where))
        # The floor of the room and the corridor, one layer (no ceiling over it).
        for p in [(8.5, 1.5), (9.5, -1.1), (5.5, -1.1), (4.5, 6.5), (0.5, 4.5)]:
            self.assertTrue(is_floor(s.at(*p)), "no floor at %s: %s%s" % (p, s.at(*p), where))
        # The walls along their lines: the north wall (y 8.0 .. 8.1), the west wall (x -0.1 .. 0) and the
        # south wall (y -0.1 .. 0) east of its door (whose lintel, 2 .. 2.5 m, is drawn too).
        # (Sampled between the grid's lines and away from the corners.)
        north = [s.at(0.25 + 0.5 * k, 8.05) for k in range(20)]
        west = [s.at(-0.05, -1.75 + 0.5 * k) for k in range(20) if abs(-1.75 + 0.5 * k) > 0.3]
        south = [s.at(2.25 + 0.5 * k, -0.05) for k in range(16)]
        for name, wall in [("north", north), ("west", west), ("south", south)]:
            self.assertTrue(all(is_wall(c) for c in wall), "the %s wall is not drawn along its line: %s%s" %
                            (name, wall, where))
        # The robot: its URDF body where it stands (heading 0), and nowhere 0.6 m from it.
        body = [s.at(START[0] + bx, START[1] + by) for bx, by in
                [(-0.15, 0.0), (-0.15, 0.12), (-0.15, -0.12), (0.1, 0.15), (0.1, -0.15), (0.18, 0.0)]]
        self.assertGreaterEqual(sum(1 for c in body if is_robot_red(c)), 5,
                                "no robot body at the start pose: %s%s" % (body, where))
        around = s.ring(START, 0.6, 0.6)
        self.assertFalse(any(is_robot_red(c) for c in around), "robot red 0.6 m from the robot" + where)

    def check_scan(self, s, where):
        # Floor points all round the robot within the scanner's reach (URG-04LX: 5.6 m), where the
        # room's floor is (the robot stands 2 m from the west wall, 3 m from the north wall).
        near = s.ring(START, 0.8, 1.6)
        share = sum(1 for c in near if is_floor_point(c)) / float(len(near))
        print("rviz screenshot after the scan: %.2f of the ring 0.8-1.6 m around the robot is floor points" % share)
        self.assertGreater(share, 0.5, "the scan's floor points are not around the robot" + where)
        # Beyond the scanner's reach the floor stays bare.
        for p in [(8.5, 1.5), (9.5, 6.5), (8.5, 0.5)]:
            self.assertTrue(is_floor(s.at(*p)), "scan points %.1f m from the scanner at %s: %s%s" %
                            (math.hypot(p[0] - START[0], p[1] - START[1]), p, s.at(*p), where))


if __name__ == "__main__":
    rospy.init_node("rviz_sim_test")
    rostest.rosrun("scanstop_sim", "rviz_sim", RvizSim)
