#!/usr/bin/python3
"""rviz/run.rviz headless, checked for what a user must see: a run directory of one perfect scan of
room_10x8 from its start (2, 5) (scan_world; map/ + mesh.ply, the map frame at the start as in a
mission), shown by view_run.launch's bpa_mesher_node; rviz under xvfb-run, full screen, with
run.rviz's displays seen from straight above (a top-down view of known scale). The screenshot must
show the room's floor around the scanner (map points and mesh at floor height, not a ceiling: the
map and the mesh are cut at 2 m for display), the north wall's points and mesh along its line, and
nothing beyond the scanner's reach; rviz must log no errors."""
import os
import re
import subprocess
import sys
import time
import unittest

import rospkg
import rospy
import rostest
from roslib.packages import find_node
from sensor_msgs.msg import PointCloud2
from visualization_msgs.msg import MarkerArray

sys.path.insert(0, os.path.join(rospkg.RosPack().get_path("scanstop_common"), "scripts"))
import rviz_screenshot  # noqa: E402
from rviz_screenshot import Screen, grey  # noqa: E402

# rviz lines that are not display errors (Debian's rviz asks rospack for an optional package).
BENIGN = [re.compile(p) for p in (r"no such package media_export", r"\[librospack\]: error while executing command")]


BACKGROUND = (48, 48, 48)    # run.rviz's Background Color
SCALE = 60.0                 # pixels per metre of the top-down view
START = (2.0, 5.0)           # room_10x8's start pose in the world: the map frame's origin
FOCUS = (3.0, -2.0)          # map point at the centre of the render panel (world (5, 3))


def tool(pkg, name):
    found = find_node(pkg, name)
    if not found:
        raise RuntimeError("%s's %s is not built" % (pkg, name))
    return found[0]


def is_background(c):
    return grey(c, BACKGROUND[0] - 4, BACKGROUND[0] + 4)


def is_floor_point(c):
    """A map point at floor height: the low end of rviz's rainbow (run.rviz: AxisColor on z, bounds
    from the data), red."""
    return c[0] >= 180 and c[1] <= 90 and c[2] <= 90


def is_high_point(c):
    """A map point near the top of the data's heights: blue to magenta (a ceiling, if one were shown)."""
    return c[2] >= 180 and c[1] <= 90


def is_wall_point(c):
    """A map point above the floor (rviz's rainbow from yellow over green and cyan to blue)."""
    return c[1] >= 150 or c[2] >= 180


class RvizScreenshot(unittest.TestCase):
    def test_rviz_shows_the_run(self):
        run_dir = rospy.get_param("~run_dir")
        config = rospy.get_param("~rviz_config")
        world = rospy.get_param("~world")
        os.makedirs(run_dir, exist_ok=True)
        # A one-scan map (the scan at the map origin, as a mission's first scan) and its mesh.
        scan = os.path.join(run_dir, "scan.pcd")
        subprocess.check_call([tool("scanstop_sim", "scan_world"), world, scan, "--pose", "%g,%g,0" % START,
                               "--planes", "100", "--profile", "perfect"])
        with open(os.path.join(run_dir, "scans.txt"), "w") as f:
            f.write("%s 0 0 0 0\n" % scan)
        subprocess.check_call([tool("scanstop_mesher", "bpa_bench"), "make_map", os.path.join(run_dir, "map"),
                               os.path.join(run_dir, "scans.txt")])
        subprocess.check_call([tool("scanstop_mesher", "bpa_mesh"), os.path.join(run_dir, "map"),
                               os.path.join(run_dir, "mesh.ply"), "--voxel", "0.05"])

        # view_run.launch's node picks both up.
        got = {}
        rospy.Subscriber("slam/map_cloud", PointCloud2, lambda m: got.__setitem__("cloud", m.width * m.height))
        rospy.Subscriber("mesher/mesh_markers", MarkerArray,
                         lambda m: got.__setitem__("mesh", sum(len(k.points) // 3 for k in m.markers)))
        deadline = time.time() + 30
        while time.time() < deadline and not (got.get("cloud", 0) > 1000 and got.get("mesh", 0) > 1000):
            time.sleep(0.2)
        self.assertGreater(got.get("cloud", 0), 1000, "no map points on slam/map_cloud")
        self.assertGreater(got.get("mesh", 0), 1000, "no mesh on mesher/mesh_markers")

        view_config = os.path.join(run_dir, "run_top_down.rviz")
        with open(config) as f, open(view_config, "w") as out:
            out.write(rviz_screenshot.top_down_config(f.read(), SCALE, FOCUS))
        shot = os.path.join(run_dir, "rviz.xwd")
        log = os.path.join(run_dir, "rviz.log")
        script = ('%s & R=$!; sleep 25; xwd -root -silent > "%s"; kill $R; wait $R; true' %
                  (rviz_screenshot.rviz_command(view_config, log), shot))
        subprocess.run(["xvfb-run", "-a", "-s", "-screen 0 1400x900x24", "bash", "-c", script], timeout=120,
                       check=True)
        s = Screen(shot, SCALE, FOCUS)
        png = os.path.join(run_dir, "rviz.png")
        s.write_png(png)
        print("screenshot: %s" % png)
        with open(log) as f:
            lines = f.read().splitlines()
        self.assertTrue(any("rviz version" in line for line in lines), "rviz did not start:\n" + "\n".join(lines))
        errors = [line for line in lines
                  if re.search(r"ERROR|FATAL|[Ff]ailed|[Ee]rror", line) and not any(b.search(line) for b in BENIGN)]
        self.assertEqual(errors, [], "rviz logged errors:\n" + "\n".join(errors))

        where = " (screenshot %s)" % png
        self.assertEqual((s.width, s.height), (1400, 900))
        # Around the scanner (the map origin): the floor, seen from above; no ceiling over it.
        near = s.ring((0.0, 0.0), 0.8, 1.6)
        floor = sum(1 for c in near if is_floor_point(c)) / float(len(near))
        ceiling = sum(1 for c in near if is_high_point(c)) / float(len(near))
        # The north wall's inner face (world y 8: map y 3), x 1.5 .. 5.5 m in the world.
        wall = [s.at(x / 20.0 - 2.0, 3.0 + dy) for x in range(30, 111) for dy in (-0.02, 0.0, 0.02)]
        mid = sum(1 for c in wall if is_wall_point(c)) / float(len(wall))
        print("around the scanner: floor points %.2f, high points %.2f; on the north wall's line: wall points %.2f" %
              (floor, ceiling, mid))
        self.assertGreater(floor, 0.3, "the floor around the scanner is not seen from above" + where)
        self.assertLess(ceiling, 0.02, "a ceiling hides the room" + where)
        self.assertGreater(mid, 0.1, "the north wall is not along its line" + where)
        # Beyond the scanner's reach (world (8.5, 1.5), (9.5, 6.5); outside the room): nothing drawn.
        for p in [(6.5, -3.5), (7.5, 1.5), (9.5, -1.5)]:
            self.assertTrue(is_background(s.at(*p)), "something drawn at %s: %s%s" % (p, s.at(*p), where))


if __name__ == "__main__":
    rospy.init_node("rviz_screenshot_test")
    try:
        rostest.rosrun("scanstop_mesher", "rviz_screenshot", RvizScreenshot)
    finally:
        run_dir = rospy.get_param("~run_dir", "")
        if run_dir.startswith("/tmp/") and not os.environ.get("VIEW_RUN_KEEP"):
            subprocess.call(["rm", "-rf", run_dir])
