#!/usr/bin/python3
"""rviz/sim.rviz headless, checked for what a user must see. sim_node runs room_10x8 with the robot
at its start (2, 5); the test takes a scan and turns the robot by 0.5 rad (so the latched scan's
stamp lies before the current pose), then starts rviz under xvfb-run with sim.rviz's displays, seen
from straight above (the one change: a top-down view of known scale, so that a world point has a
known pixel) and takes a screenshot. It must show
  - the room's floor (the world mesh, not the background) where the scanner cannot reach, and no
    ceiling over it (sim_node leaves it out of sim/world_mesh: world_display_max_z_m);
  - the walls: the scan's points on the north wall, coloured by height (mid heights green), along the
    wall's line, and none of those colours on the floor between the robot and the wall;
  - the robot, drawn from its URDF (the red body of config/robot_body.yaml) where the robot stands,
    turned as it is;
and rviz must log no errors."""
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import unittest

import rospkg
import rospy
import rostest
from scanstop_msgs.srv import Rotate, TakeScan

sys.path.insert(0, os.path.join(rospkg.RosPack().get_path("scanstop_common"), "scripts"))
import xwd_image  # noqa: E402

# rviz lines that are not display errors (Debian's rviz asks rospack for an optional package).
BENIGN = [re.compile(p) for p in (r"no such package media_export", r"\[librospack\]: error while executing command")]

BACKGROUND = (48, 48, 48)      # sim.rviz's Background Color
SCALE = 60.0                   # pixels per metre of the top-down view
FOCUS = (5.0, 3.0)             # world point at the centre of the render panel
START = (2.0, 5.0)             # room_10x8's start pose (world frame)
TURN = 0.5                     # [rad] the robot's heading when the screenshot is taken


def top_down(config_text):
    """sim.rviz with the view replaced by a top-down orthographic one and the displays panel hidden."""
    view = ("  Views:\n    Current:\n      Angle: 0\n      Class: rviz/TopDownOrtho\n      Invert Z Axis: false\n"
            "      Name: Current View\n      Near Clip Distance: 0.01\n      Scale: %g\n"
            "      Target Frame: <Fixed Frame>\n      X: %g\n      Y: %g\n    Saved: ~\n" % (SCALE, FOCUS[0], FOCUS[1]))
    text, n = re.subn(r"  Views:\n    Current:\n(?:      .*\n|        .*\n)*    Saved: ~\n", view, config_text)
    if n != 1:
        raise ValueError("sim.rviz: no Views section to replace")
    return text.replace("Hide Left Dock: false", "Hide Left Dock: true")


class Screen(object):
    """The screenshot and the world -> pixel map of its render panel."""

    def __init__(self, path):
        self.width, self.height, self.rows = xwd_image.read_xwd(path)
        box = xwd_image.bounding_box(self.width, self.height, self.rows, BACKGROUND)
        if box is None:
            raise AssertionError("no rviz render panel (no background colour) in %s" % path)
        self.box = box
        self.cx, self.cy = (box[0] + box[2]) / 2.0, (box[1] + box[3]) / 2.0

    def at(self, x, y):
        px = int(round(self.cx + (x - FOCUS[0]) * SCALE))
        py = int(round(self.cy - (y - FOCUS[1]) * SCALE))
        return xwd_image.pixel(self.rows, px, py)

    def pixels_along(self, a, b, across_m=0.06):
        """Every pixel of the strip from world point a to b, `across_m` wide."""
        n = int(math.hypot(b[0] - a[0], b[1] - a[1]) * SCALE)
        ux, uy = (b[0] - a[0]) / max(n, 1), (b[1] - a[1]) / max(n, 1)
        norm = math.hypot(ux, uy) or 1.0
        vx, vy = -uy / norm / SCALE, ux / norm / SCALE
        k = int(across_m * SCALE / 2)
        return [self.at(a[0] + i * ux + j * vx, a[1] + i * uy + j * vy) for i in range(n + 1) for j in range(-k, k + 1)]


def is_background(c):
    return all(abs(c[i] - BACKGROUND[i]) <= 6 for i in range(3))


def is_floor(c):
    """The translucent grey world mesh over the background: grey, and lighter than the background."""
    return max(c) - min(c) <= 20 and min(c) >= BACKGROUND[0] + 15


def is_green(c):
    """A scan point at mid height (sim.rviz colours points by z in rviz's rainbow: 0 m magenta, 1.2 m green)."""
    return c[1] >= 120 and c[1] >= c[0] + 60 and c[1] >= c[2] - 40


def is_robot_red(c):
    """The URDF's body (0.75, 0.1, 0.1), lit from above."""
    return c[0] >= 90 and c[0] >= 2 * c[1] and c[0] >= 2 * c[2]


class RvizSim(unittest.TestCase):
    def test_rviz_shows_room_walls_and_robot(self):
        config = rospy.get_param("~rviz_config")
        rospy.wait_for_service("scanner/take_scan", 60)
        scan = rospy.ServiceProxy("scanner/take_scan", TakeScan)(planes=200)
        self.assertTrue(scan.success, scan.message)
        turn = rospy.ServiceProxy("base/rotate", Rotate)(angle_rad=TURN)
        self.assertTrue(turn.success, turn.message)

        work = tempfile.mkdtemp(prefix="rviz_sim_")
        keep = os.environ.get("RVIZ_SIM_KEEP")
        try:
            view_config = os.path.join(work, "sim_top_down.rviz")
            with open(config) as f, open(view_config, "w") as out:
                out.write(top_down(f.read()))
            # Two screenshots, after 20 s and 35 s (a loaded machine renders slowly); the later one
            # counts unless it shows no robot yet.
            shots = [os.path.join(work, "rviz%d.xwd" % k) for k in (1, 2)]
            log = os.path.join(work, "rviz.log")
            script = ('rviz -d "%s" > "%s" 2>&1 & R=$!; sleep 20; xwd -root -silent > "%s"; sleep 15; '
                      'xwd -root -silent > "%s"; kill $R; wait $R; true' % (view_config, log, shots[0], shots[1]))
            subprocess.run(["xvfb-run", "-a", "-s", "-screen 0 1400x900x24", "bash", "-c", script], timeout=150,
                           check=True)
            with open(log) as f:
                lines = f.read().splitlines()
            screen = Screen(shots[1])
            png = os.path.join(work, "rviz.png")
            xwd_image.write_png(png, screen.width, screen.height, screen.rows)
            if keep:
                shutil.copy(png, keep)
            self.check_screen(screen, keep or png)
        finally:
            shutil.rmtree(work, ignore_errors=True)
        self.assertTrue(any("rviz version" in line for line in lines), "rviz did not start:\n" + "\n".join(lines))
        errors = [line for line in lines
                  if re.search(r"ERROR|FATAL|[Ff]ailed|[Ee]rror", line) and not any(b.search(line) for b in BENIGN)]
        self.assertEqual(errors, [], "rviz logged errors:\n" + "\n".join(errors))

    def check_screen(self, s, png):
        where = " (screenshot %s, render panel %s)" % (png, s.box)
        self.assertEqual((s.width, s.height), (1400, 900))
        # The panel: wider than 1000 px with the displays panel hidden, and the view's centre in it.
        self.assertGreater(s.box[2] - s.box[0], 1000, "the render panel is too small" + where)
        # Outside the world: the background.
        for p in [(12.5, 3.0), (-2.5, 3.5)]:
            self.assertTrue(is_background(s.at(*p)), "%s is not background: %s%s" % (p, s.at(*p), where))
        # The floor (room and corridor) where the scanner could not reach (over 5.6 m from the start):
        # the world's floor, not the background: no ceiling hides it, and it is drawn.
        for p in [(8.5, 1.5), (9.5, -1.1), (5.5, -1.1), (8.5, 0.5)]:
            self.assertTrue(is_floor(s.at(*p)), "no floor at %s: %s%s" % (p, s.at(*p), where))
        # The north wall's inner face (y = 8) seen from the start: green scan points along its line.
        wall = s.pixels_along((1.5, 8.0), (5.5, 8.0))
        on_wall = sum(1 for c in wall if is_green(c)) / float(len(wall))
        floor = s.pixels_along((1.5, 6.8), (5.5, 6.8))
        on_floor = sum(1 for c in floor if is_green(c)) / float(len(floor))
        print("rviz screenshot: panel %s; green on the north wall %.3f, on the floor before it %.3f" %
              (s.box, on_wall, on_floor))
        self.assertGreater(on_wall, 0.05, "the north wall's scan points are not on its line" + where)
        self.assertLess(on_floor, on_wall / 5.0, "mid-height points on the floor" + where)
        # The robot: its body behind the centre (the axes, arrows and the URG are on or ahead of it).
        c, s_ = math.cos(TURN), math.sin(TURN)
        body = []
        for bx, by in [(-0.15, 0.0), (-0.15, 0.12), (-0.15, -0.12), (-0.1, 0.15), (-0.1, -0.15)]:
            body.append(s.at(START[0] + c * bx - s_ * by, START[1] + s_ * bx + c * by))
        red = sum(1 for px in body if is_robot_red(px))
        self.assertGreaterEqual(red, 4, "no robot body at the start pose: %s%s" % (body, where))
        # ... and not where it is not (0.6 m behind it: the floor and magenta floor points).
        behind = s.at(START[0] - c * 0.6, START[1] - s_ * 0.6)
        self.assertFalse(is_robot_red(behind), "robot red 0.6 m behind the robot: %s%s" % (behind, where))


if __name__ == "__main__":
    rospy.init_node("rviz_sim_test")
    rostest.rosrun("scanstop_sim", "rviz_sim", RvizSim)
