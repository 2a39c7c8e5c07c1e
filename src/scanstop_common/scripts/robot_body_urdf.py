#!/usr/bin/python3
"""Writes the robot's URDF (robot_description, for rviz's RobotModel) from config/robot_body.yaml,
the one description of the body that sim_node, explorer_node and mission_node read too.

usage: robot_body_urdf.py ROBOT_BODY_YAML [--out FILE]

One link, base_link (REP-105: on the floor, x forward), with visuals only: the collision disc
(radius, translucent, what every node plans and checks with), the body box (length x width x
body_height), the mast up to `height` at mast_x and the URG on top. No joints: the drivers
publish base_link and the laser frame on tf, so no robot_state_publisher is needed.
Exit 1 with the file and the field named on a missing file, a missing or bad field.
"""
import argparse
import math
import sys

import yaml

FIELDS = {  # name: (lo, hi) [m]
    "radius": (1e-3, 2.0),
    "height": (1e-3, 3.0),
    "length": (1e-3, 4.0),
    "width": (1e-3, 4.0),
    "body_height": (1e-3, 3.0),
    "mast_x": (-2.0, 2.0),
}


def load_body(path):
    """The robot_body mapping of PATH, checked; raises ValueError naming the file and the field."""
    try:
        with open(path) as f:
            doc = yaml.safe_load(f)
    except OSError as e:
        raise ValueError("%s: cannot read: %s" % (path, e.strerror or e))
    except yaml.YAMLError as e:
        raise ValueError("%s: not YAML: %s" % (path, e))
    body = doc.get("robot_body") if isinstance(doc, dict) else None
    if not isinstance(body, dict):
        raise ValueError("%s: no 'robot_body' mapping" % path)
    out = {}
    for name, (lo, hi) in FIELDS.items():
        if name not in body:
            raise ValueError("%s: robot_body/%s is missing" % (path, name))
        v = body[name]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or not lo <= v <= hi:
            raise ValueError("%s: robot_body/%s = %r must be a number in [%g, %g] m" % (path, name, v, lo, hi))
        out[name] = float(v)
    if out["body_height"] > out["height"]:
        raise ValueError("%s: robot_body/body_height %g m is above robot_body/height %g m" %
                         (path, out["body_height"], out["height"]))
    for name in sorted(set(body) - set(FIELDS)):
        sys.stderr.write("robot_body_urdf: %s: ignoring unknown field robot_body/%s\n" % (path, name))
    return out


def urdf(b):
    """The URDF text of body b (load_body's mapping)."""
    mast_r, urg = 0.02, (0.05, 0.05, 0.07)
    mast_top = b["height"] - urg[2]
    mast_len = max(mast_top - b["body_height"], 1e-3)

    def visual(name, geometry, xyz, rgba):
        return ('    <visual name="%s">\n      <origin xyz="%g %g %g" rpy="0 0 0"/>\n'
                '      <geometry>%s</geometry>\n      <material name="%s"><color rgba="%s"/></material>\n'
                '    </visual>\n' % (name, xyz[0], xyz[1], xyz[2], geometry, name, rgba))

    return ('<?xml version="1.0"?>\n'
            '<!-- written by robot_body_urdf.py from config/robot_body.yaml: edit that file, not this -->\n'
            '<robot name="pioneer2dx_rotating_urg">\n  <link name="base_link">\n' +
            visual("collision_disc", '<cylinder radius="%g" length="0.01"/>' % b["radius"], (0, 0, 0.005),
                   "1 0.5 0 0.35") +
            visual("body", '<box size="%g %g %g"/>' % (b["length"], b["width"], b["body_height"] - 0.05),
                   (0, 0, 0.05 + (b["body_height"] - 0.05) / 2), "0.75 0.1 0.1 1") +
            visual("mast", '<cylinder radius="%g" length="%g"/>' % (mast_r, mast_len),
                   (b["mast_x"], 0, b["body_height"] + mast_len / 2), "0.3 0.3 0.3 1") +
            visual("urg", '<box size="%g %g %g"/>' % urg, (b["mast_x"], 0, mast_top + urg[2] / 2), "0.1 0.1 0.1 1") +
            '  </link>\n</robot>\n')


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("yaml")
    ap.add_argument("--out", help="write here instead of stdout")
    args = ap.parse_args(argv)
    try:
        text = urdf(load_body(args.yaml))
    except ValueError as e:
        sys.stderr.write("robot_body_urdf: %s\n" % e)
        return 1
    if args.out:
        try:
            with open(args.out, "w") as f:
                f.write(text)
        except OSError as e:
            sys.stderr.write("robot_body_urdf: %s: cannot write: %s\n" % (args.out, e.strerror or e))
            return 1
    else:
        sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
