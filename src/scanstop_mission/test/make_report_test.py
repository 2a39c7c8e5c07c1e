#!/usr/bin/env python3
"""make_report.py on synthetic run directories (a few poses, a floor map): the plots and report.html
are written, the pose error plot only with true poses, and a broken input (no map/poses.csv, a garbage
line) ends it with exit status 1 naming the file, with nothing written or deleted.

Run by run_tests_scanstop_mission (catkin_run_tests_target make_report); a few seconds."""
import importlib.util
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

PKG = "scanstop_mission"
SCRIPT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts", "make_report.py")
HEADER = ("index,file,stamp_s,map_x,map_y,map_yaw,odom_x,odom_y,odom_yaw,sensor_x,sensor_y,sensor_z,converged,"
          "iterations,correspondences,rms_m,overlap\n")
PNGS = ["report_coverage.png", "report_trajectory.png", "report_pose_error.png"]


def make_run(root, truth=True, summary=True, floor=True, mission_times=False):
    """A run directory of 4 scans along a 4 x 3 m room; returns its path."""
    run = os.path.join(root, "run")
    os.makedirs(os.path.join(run, "map"))
    os.makedirs(os.path.join(run, "explorer"))
    poses = [(0.0, 0.0, 0.0), (1.0, 0.1, 0.5), (2.0, 1.0, 1.6), (2.5, 2.0, 3.0)]
    with open(os.path.join(run, "map", "poses.csv"), "w") as f:
        f.write(HEADER)
        for i, (x, y, yaw) in enumerate(poses):
            f.write("%d,scans/scan_%04d.pcd,%g,%g,%g,%g,%g,%g,%g,0,0,0.45,1,10,1000,0.01,0.9\n" %
                    (i, i, 41.0 + 50.0 * i, x, y, yaw, x * 1.1, y * 0.9, yaw + 0.05 * i))
    lines = ["state: DONE", "world: synthetic", "coverage: 0.9", "modelled_time_s: 200", "scans:"]
    for i, (x, y, yaw) in enumerate(poses):
        lines += ["  - index: %d" % i, "    map_pose: [%g, %g, %g]" % (x, y, yaw), "    scan_time_s: 40",
                  "    coverage: %g" % (0.3 + 0.2 * i)]
        if mission_times:
            lines.append("    mission_time_s: %g" % (60.0 + 90.0 * i))
        if truth:
            lines.append("    true_pose: [%g, %g, %g]" % (x + 0.01 * i, y - 0.02 * i, yaw + 0.002 * i))
    with open(os.path.join(run, "mission_state.yaml"), "w") as f:
        f.write("\n".join(lines) + "\n")
    if summary:
        with open(os.path.join(run, "summary.json"), "w") as f:
            json.dump({"world": "synthetic", "state": "DONE", "scans": 4, "coverage": 0.9,
                       "true_coverage": 0.85 if truth else None, "collisions": 0, "modelled_time_s": 420.0,
                       "modelled_scanning_s": 160.0, "modelled_driving_s": 240.0, "modelled_compute_s": 20.0,
                       "surface_coverage": 0.913 if truth else None,
                       "mesh_triangles": 3404278 if truth else None,
                       "mesh_distance_median_m": 0.0029 if truth else None,
                       "mesh_distance_rms_m": 0.0076 if truth else None,
                       "mesh_distance_p95_m": 0.0173 if truth else None,
                       "mesh_surface_coverage": 0.923 if truth else None}, f)
    if floor:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.image as mpimg
        import numpy as np
        img = np.full((60, 80), 205, dtype=np.uint8)  # 3 x 4 m at 0.05 m, unknown
        img[5:55, 5:75] = 254
        img[5, 5:75] = img[54, 5:75] = 0
        img[5:55, 5] = img[5:55, 74] = 0
        mpimg.imsave(os.path.join(run, "explorer", "floor_map.png"), img, cmap="gray", vmin=0, vmax=255)
        with open(os.path.join(run, "explorer", "floor_map.yaml"), "w") as f:
            f.write("image: floor_map.png\nresolution: 0.05\norigin: [-0.5, -0.5, 0.0]\nnegate: 0\n")
    with open(os.path.join(run, "report.md"), "w") as f:
        f.write("# Exploration report\n")
    return run


def listing(run):
    out = {}
    for d, _, files in os.walk(run):
        for name in files:
            p = os.path.join(d, name)
            with open(p, "rb") as f:
                out[os.path.relpath(p, run)] = f.read()
    return out


class MakeReport(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="make_report_test_")

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def run_script(self, run):
        return subprocess.run([sys.executable, SCRIPT, run], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                              universal_newlines=True, timeout=120)

    def assertPng(self, path):
        self.assertTrue(os.path.isfile(path), path)
        with open(path, "rb") as f:
            self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n", path)
        self.assertGreater(os.path.getsize(path), 5000, path)

    def test_simulated_run_all_plots_and_html(self):
        run = make_run(self.tmp)
        r = self.run_script(run)
        self.assertEqual(r.returncode, 0, r.stderr)
        for png in PNGS:
            self.assertPng(os.path.join(run, png))
        with open(os.path.join(run, "report.html")) as f:
            page = f.read()
        for png in PNGS:
            self.assertIn('src="%s"' % png, page)
        self.assertIn("synthetic", page)
        self.assertIn("85.0 %", page)  # the true coverage
        self.assertIn("SLAM position error (4 scans)", page)
        self.assertIn("91.3 %", page)  # the surface held by the map
        self.assertIn("2.9 mm / 7.6 mm / 17.3 mm; 92.3 % (3404278 triangles)", page)  # the mesh against the world
        self.assertIn("2.7 min / 4.0 min / 0.3 min", page)  # scanning / driving / compute
        self.assertNotIn("no explorer/floor_map.yaml", page)
        self.assertEqual([n for n in os.listdir(run) if n.startswith(".tmp_")], [])

    def test_coverage_against_the_missions_modelled_time_when_the_state_has_it(self):
        spec = importlib.util.spec_from_file_location("make_report", SCRIPT)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        # With mission_time_s: the mission's clock (scanning, driving and compute) of each coverage.
        run = module.Run(make_run(os.path.join(self.tmp, "a"), mission_times=True))
        self.assertEqual(run.time_min, [1.0, 2.5, 4.0, 5.5])
        # Without it (an older run): the map's stamps (41 s + 50 s per scan) from the start of the
        # first scan (its stamp less its 40 s scan time).
        run = module.Run(make_run(os.path.join(self.tmp, "b")))
        for got, want in zip(run.time_min, [40.0, 90.0, 140.0, 190.0]):
            self.assertAlmostEqual(got, want / 60.0)

    def test_robot_run_without_truth_has_no_error_plot(self):
        run = make_run(self.tmp, truth=False, floor=False)
        r = self.run_script(run)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertPng(os.path.join(run, "report_coverage.png"))
        self.assertPng(os.path.join(run, "report_trajectory.png"))
        self.assertFalse(os.path.exists(os.path.join(run, "report_pose_error.png")))
        with open(os.path.join(run, "report.html")) as f:
            page = f.read()
        self.assertNotIn("report_pose_error.png", page)
        self.assertIn("no true poses", page)
        self.assertIn("no true coverage", page)
        self.assertIn("no explorer/floor_map.yaml", page)

    def test_live_run_without_summary(self):
        run = make_run(self.tmp, summary=False)
        r = self.run_script(run)
        self.assertEqual(r.returncode, 0, r.stderr)
        with open(os.path.join(run, "report.html")) as f:
            self.assertIn("no summary.json", f.read())

    def assertFailsUnchanged(self, run, expected):
        before = listing(run)
        r = self.run_script(run)
        self.assertEqual(r.returncode, 1, r.stdout + r.stderr)
        self.assertIn(expected, r.stderr)
        self.assertIn("nothing written", r.stderr)
        self.assertEqual(listing(run), before)  # nothing written, nothing deleted

    def test_missing_poses_csv_names_the_file(self):
        run = make_run(self.tmp)
        os.unlink(os.path.join(run, "map", "poses.csv"))
        self.assertFailsUnchanged(run, os.path.join(run, "map", "poses.csv") + ": missing")

    def test_garbage_line_names_file_and_line(self):
        run = make_run(self.tmp)
        path = os.path.join(run, "map", "poses.csv")
        with open(path) as f:
            lines = f.readlines()
        lines[2] = "1,scans/scan_0001.pcd,91,zz,0.1,0.5,1,1,1,0,0,0.45,1,10,1000,0.01,0.9\n"
        lines.append("garbage\n")
        with open(path, "w") as f:
            f.writelines(lines)
        self.assertFailsUnchanged(run, path + " line 3: not a number")
        lines[2] = "truncated,line\n"
        with open(path, "w") as f:
            f.writelines(lines)
        self.assertFailsUnchanged(run, path + " line 3: 2 fields, the header has 17")

    def test_garbage_mission_state_names_the_file(self):
        run = make_run(self.tmp)
        with open(os.path.join(run, "mission_state.yaml"), "a") as f:
            f.write("scans: [unclosed\n")
        self.assertFailsUnchanged(run, os.path.join(run, "mission_state.yaml") + ": not YAML")

    def test_scan_ticks_are_integers(self):
        sys.path.insert(0, os.path.dirname(SCRIPT))
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        import make_report
        run = make_report.Run(make_run(self.tmp))
        captured = []
        orig = make_report.atomic_savefig
        make_report.atomic_savefig = lambda fig, path: captured.append(fig) or orig(fig, path)
        try:
            make_report.plot_coverage(run, plt, os.path.join(self.tmp, "c.png"))
            make_report.plot_pose_error(run, plt, os.path.join(self.tmp, "e.png"))
        finally:
            make_report.atomic_savefig = orig
        for fig in captured:
            ax = fig.axes[0] if fig.axes[0].get_xlabel() else fig.axes[-1]
            ticks = [t for t in ax.get_xticks() if ax.get_xlim()[0] <= t <= ax.get_xlim()[1]]
            self.assertTrue(ticks)
            for t in ticks:
                self.assertTrue(math.isclose(t, round(t)), ticks)


if __name__ == "__main__":
    import rosunit
    rosunit.unitrun(PKG, "make_report", MakeReport, sys.argv)
