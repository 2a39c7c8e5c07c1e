#!/usr/bin/python3
"""rviz/run.rviz headless: a run directory made from a real recorded scan (map/ + mesh.ply),
shown by view_run.launch's bpa_mesher_node; rviz under xvfb-run; the screenshot must show more
than an empty scene and rviz must log no errors."""
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
import xwd_image  # noqa: E402

# rviz lines that are not display errors (Debian's rviz asks rospack for an optional package).
BENIGN = [re.compile(p) for p in (r"no such package media_export", r"\[librospack\]: error while executing command")]


def tool(name):
    found = find_node("scanstop_mesher", name)
    if not found:
        raise RuntimeError("scanstop_mesher's %s is not built" % name)
    return found[0]


class RvizScreenshot(unittest.TestCase):
    def test_rviz_shows_the_run(self):
        run_dir = rospy.get_param("~run_dir")
        config = rospy.get_param("~rviz_config")
        scan = rospy.get_param("~scan")
        os.makedirs(run_dir, exist_ok=True)
        # A one-scan map (the scan's sensor at the map origin) and its mesh.
        with open(os.path.join(run_dir, "scans.txt"), "w") as f:
            f.write("%s 0 0 0 0\n" % scan)
        subprocess.check_call([tool("bpa_bench"), "make_map", os.path.join(run_dir, "map"),
                               os.path.join(run_dir, "scans.txt")])
        subprocess.check_call([tool("bpa_mesh"), os.path.join(run_dir, "map"), os.path.join(run_dir, "mesh.ply"),
                               "--voxel", "0.05"])

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

        # Two screenshots, after 20 s and 30 s (a loaded machine renders slowly); the richer counts.
        shots = [os.path.join(run_dir, "rviz%d.xwd" % k) for k in (1, 2)]
        log = os.path.join(run_dir, "rviz.log")
        script = ('rviz -d "%s" > "%s" 2>&1 & R=$!; sleep 20; xwd -root -silent > "%s"; sleep 10; '
                  'xwd -root -silent > "%s"; kill $R; wait $R; true' % (config, log, shots[0], shots[1]))
        subprocess.run(["xvfb-run", "-a", "-s", "-screen 0 1400x900x24", "bash", "-c", script], timeout=120,
                       check=True)
        best = None
        for shot in shots:
            width, height, rows = xwd_image.read_xwd(shot)
            colors = xwd_image.distinct_colors(rows)
            if best is None or colors > best[0]:
                best = (colors, width, height, rows)
        colors, width, height, rows = best
        png = os.path.join(run_dir, "rviz.png")
        xwd_image.write_png(png, width, height, rows)
        print("screenshot: %s (%d colours)" % (png, colors))
        self.assertEqual((width, height), (1400, 900))
        # An empty rviz (panels and a grid on a plain background) has under 1000 colours; the
        # shaded mesh and the height-coloured points add thousands.
        self.assertGreater(colors, 2000, "the screenshot looks empty (%d colours): %s" % (colors, png))

        with open(log) as f:
            lines = f.read().splitlines()
        self.assertTrue(any("rviz version" in line for line in lines), "rviz did not start:\n" + "\n".join(lines))
        errors = [line for line in lines
                  if re.search(r"ERROR|FATAL|[Ff]ailed|[Ee]rror", line) and not any(b.search(line) for b in BENIGN)]
        self.assertEqual(errors, [], "rviz logged errors:\n" + "\n".join(errors))


if __name__ == "__main__":
    rospy.init_node("rviz_screenshot_test")
    try:
        rostest.rosrun("scanstop_mesher", "rviz_screenshot", RvizScreenshot)
    finally:
        run_dir = rospy.get_param("~run_dir", "")
        if run_dir.startswith("/tmp/") and not os.environ.get("VIEW_RUN_KEEP"):
            subprocess.call(["rm", "-rf", run_dir])
