#!/usr/bin/python3
"""robot_body_urdf.py: the URDF carries config/robot_body.yaml's numbers (the one body description)
as a well-formed robot with base_link; a bad body file ends it with exit 1 naming the file and the
field, writing nothing. Run by run_tests_scanstop_common (catkin_run_tests_target); a second."""
import os
import shutil
import subprocess
import sys
import tempfile
import unittest
import xml.etree.ElementTree as ET

import yaml

PKG = "scanstop_common"
HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPT = os.path.join(HERE, "..", "scripts", "robot_body_urdf.py")
BODY = os.path.join(HERE, "..", "..", "..", "config", "robot_body.yaml")


def run(*args):
    return subprocess.run(["/usr/bin/python3", SCRIPT] + list(args), capture_output=True, text=True, timeout=30)


class RobotBodyUrdf(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="robot_body_urdf_")

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def write(self, body):
        path = os.path.join(self.tmp, "body.yaml")
        with open(path, "w") as f:
            yaml.safe_dump({"robot_body": body}, f)
        return path

    def test_urdf_has_the_numbers_of_robot_body_yaml(self):
        with open(BODY) as f:
            body = yaml.safe_load(f)["robot_body"]
        r = run(BODY)
        self.assertEqual(r.returncode, 0, r.stderr)
        robot = ET.fromstring(r.stdout)
        self.assertEqual(robot.tag, "robot")
        links = robot.findall("link")
        self.assertEqual([l.get("name") for l in links], ["base_link"])
        visuals = {v.get("name"): v for v in links[0].findall("visual")}
        self.assertEqual(set(visuals), {"collision_disc", "body", "mast", "urg"})
        disc = visuals["collision_disc"].find("geometry/cylinder")
        self.assertAlmostEqual(float(disc.get("radius")), body["radius"])
        size = [float(v) for v in visuals["body"].find("geometry/box").get("size").split()]
        self.assertAlmostEqual(size[0], body["length"])
        self.assertAlmostEqual(size[1], body["width"])
        # the URG's top is the body's height; the mast stands at mast_x
        urg = visuals["urg"]
        z = float(urg.find("origin").get("xyz").split()[2])
        h = float(urg.find("geometry/box").get("size").split()[2])
        self.assertAlmostEqual(z + h / 2, body["height"])
        self.assertAlmostEqual(float(visuals["mast"].find("origin").get("xyz").split()[0]), body["mast_x"])

    def test_a_changed_radius_changes_the_model(self):
        with open(BODY) as f:
            body = yaml.safe_load(f)["robot_body"]
        body["radius"] = 0.41
        r = run(self.write(body))
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn('radius="0.41"', r.stdout)

    def test_bad_body_names_file_and_field_and_writes_nothing(self):
        with open(BODY) as f:
            good = yaml.safe_load(f)["robot_body"]
        out = os.path.join(self.tmp, "robot.urdf")
        cases = [
            (dict(good, radius=-0.2), "robot_body/radius"),
            (dict(good, height="tall"), "robot_body/height"),
            ({k: v for k, v in good.items() if k != "width"}, "robot_body/width is missing"),
            (dict(good, body_height=good["height"] + 0.5), "robot_body/body_height"),
        ]
        for body, expected in cases:
            path = self.write(body)
            r = run(path, "--out", out)
            self.assertEqual(r.returncode, 1, (body, r.stdout))
            self.assertIn(path, r.stderr)
            self.assertIn(expected, r.stderr)
            self.assertFalse(os.path.exists(out))
        r = run(os.path.join(self.tmp, "missing.yaml"))
        self.assertEqual(r.returncode, 1)
        self.assertIn("missing.yaml: cannot read", r.stderr)
        with open(os.path.join(self.tmp, "list.yaml"), "w") as f:
            f.write("- 1\n- 2\n")
        r = run(os.path.join(self.tmp, "list.yaml"))
        self.assertEqual(r.returncode, 1)
        self.assertIn("no 'robot_body' mapping", r.stderr)


if __name__ == "__main__":
    import rosunit
    rosunit.unitrun(PKG, "robot_body_urdf", RobotBodyUrdf, sys.argv)
