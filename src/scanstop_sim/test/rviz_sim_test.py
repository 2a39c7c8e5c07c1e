#!/usr/bin/python3
"""rviz/sim.rviz headless: after a scan and a turn (so the latched scan's stamp lies before the
current pose), rviz under xvfb-run must show the world and the scan (many colours: the scan is
drawn in rainbow colours over the grey world) and log no errors."""
import os
import re
import shutil
import struct
import subprocess
import tempfile
import unittest

import rospy
import rostest
from scanstop_msgs.srv import Rotate, TakeScan

# rviz lines that are not display errors (Debian's rviz asks rospack for an optional package).
BENIGN = [re.compile(p) for p in (r"no such package media_export", r"\[librospack\]: error while executing command")]


def xwd_colours(path):
    """Number of distinct RGB values of a TrueColor ZPixmap XWD screenshot (4 bytes per pixel, as
    Xvfb at depth 24 writes it), and its width and height."""
    with open(path, "rb") as f:
        data = f.read()
    fields = struct.unpack(">25I", data[:100])
    header_size, pixmap_format, width, height = fields[0], fields[2], fields[4], fields[5]
    byte_order, bits_per_pixel, bytes_per_line, ncolors = fields[7], fields[11], fields[12], fields[19]
    rgb_mask = fields[14] | fields[15] | fields[16]
    if pixmap_format != 2 or bits_per_pixel not in (24, 32) or bytes_per_line != 4 * width:
        raise ValueError("%s: expected a ZPixmap with 4 bytes per pixel, got format %d, %d bits, %d bytes per line "
                         "for %d pixels" % (path, pixmap_format, bits_per_pixel, bytes_per_line, width))
    start = header_size + 12 * ncolors
    if len(data) < start + bytes_per_line * height:
        raise ValueError("%s: truncated" % path)
    fmt = ("<" if byte_order == 0 else ">") + "%dI" % width
    colours = set()
    for y in range(height):
        row = struct.unpack_from(fmt, data, start + y * bytes_per_line)
        colours.update(p & rgb_mask for p in row)
    return len(colours), width, height


class RvizSim(unittest.TestCase):
    def test_rviz_shows_world_robot_and_scan(self):
        config = rospy.get_param("~rviz_config")
        rospy.wait_for_service("scanner/take_scan", 60)
        scan = rospy.ServiceProxy("scanner/take_scan", TakeScan)(planes=200)
        self.assertTrue(scan.success, scan.message)
        turn = rospy.ServiceProxy("base/rotate", Rotate)(angle_rad=0.5)
        self.assertTrue(turn.success, turn.message)

        work = tempfile.mkdtemp(prefix="rviz_sim_")
        try:
            # Two screenshots, after 20 s and 35 s (a loaded machine renders slowly); the richer counts.
            shots = [os.path.join(work, "rviz%d.xwd" % k) for k in (1, 2)]
            log = os.path.join(work, "rviz.log")
            script = ('rviz -d "%s" > "%s" 2>&1 & R=$!; sleep 20; xwd -root -silent > "%s"; sleep 15; '
                      'xwd -root -silent > "%s"; kill $R; wait $R; true' % (config, log, shots[0], shots[1]))
            subprocess.run(["xvfb-run", "-a", "-s", "-screen 0 1400x900x24", "bash", "-c", script], timeout=150,
                           check=True)
            counted = [xwd_colours(shot) + (shot,) for shot in shots]
            colours, width, height, shot = max(counted)
            with open(log) as f:
                lines = f.read().splitlines()
            print("rviz screenshot: %dx%d, %d colours" % (width, height, colours))
            if os.environ.get("RVIZ_SIM_KEEP"):
                shutil.copy(shot, os.environ["RVIZ_SIM_KEEP"])
        finally:
            shutil.rmtree(work, ignore_errors=True)
        self.assertEqual((width, height), (1400, 900))
        self.assertTrue(any("rviz version" in line for line in lines), "rviz did not start:\n" + "\n".join(lines))
        errors = [line for line in lines
                  if re.search(r"ERROR|FATAL|[Ff]ailed|[Ee]rror", line) and not any(b.search(line) for b in BENIGN)]
        self.assertEqual(errors, [], "rviz logged errors:\n" + "\n".join(errors))
        # rviz with the world, grid and robot but no scan: 8,800 colours (measured); with a scan
        # drawn in rainbow colours 27,000 (100 planes) to 47,000 (200-400 planes, room and house).
        self.assertGreater(colours, 15000, "the screenshot shows no scan (%d colours)" % colours)


if __name__ == "__main__":
    rospy.init_node("rviz_sim_test")
    rostest.rosrun("scanstop_sim", "rviz_sim", RvizSim)
