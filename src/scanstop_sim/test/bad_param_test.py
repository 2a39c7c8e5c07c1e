#!/usr/bin/env python3
"""Starts sim_node with one bad parameter at a time: it must exit non-zero at once with a FATAL
message naming the parameter, its value and the allowed range (issue 9). Run by bad_param.test
(the rostest provides the master)."""
import os
import subprocess
import sys
import unittest

import rospkg
import rostest

PKG = 'scanstop_sim'
WORLD = os.path.join(rospkg.RosPack().get_path(PKG), '..', '..', 'worlds', 'room_10x8.stl')


def node_binary():
    import roslib.packages
    found = roslib.packages.find_node(PKG, 'sim_node')
    if not found:
        raise RuntimeError('sim_node is not built')
    return found[0]


class BadParameters(unittest.TestCase):
    def run_node(self, index, params):
        args = [node_binary(), '__name:=bad_sim_node_%d' % index] + ['_%s:=%s' % kv for kv in params]
        proc = subprocess.run(args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=60,
                              universal_newlines=True)
        return proc.returncode, proc.stdout

    def check(self, index, params, *expected):
        rc, out = self.run_node(index, [('world', WORLD)] + params)
        self.assertNotEqual(rc, 0, 'sim_node with %s kept running or exited 0:\n%s' % (params, out))
        self.assertIn('FATAL', out, out)
        for text in expected:
            self.assertIn(text, out, 'expected %r in the output for %s:\n%s' % (text, params, out))

    def test_scanner_height_out_of_range(self):
        self.check(1, [('scanner/height_m', '7.0')], "'scanner/height_m' = 7 m is out of range [0.05, 3 m]")

    def test_negative_plane_time(self):
        self.check(2, [('scanner/plane_time_s', '-0.1')], "'scanner/plane_time_s' = -0.1 s is out of range [0.001, 10 s]")

    def test_absurd_max_forward(self):
        self.check(3, [('max_forward_m', '1000.0')], "'max_forward_m' = 1000 m is out of range [0.1, 100 m]")

    def test_absurd_max_rotate(self):
        self.check(4, [('max_rotate_rad', '50.0')], "'max_rotate_rad' = 50 rad is out of range")

    def test_speed_beyond_the_pioneer(self):
        self.check(5, [('motion/linear_speed_mps', '20.0')], "'motion/linear_speed_mps' = 20 m/s is out of range [0.01, 1.5 m/s]")

    def test_profile_value_names_the_profile_parameter(self):
        self.check(6, [('error_profile', 'thesis'), ('profiles/thesis/sensor/p_hit', '-1.0')],
                   "'profiles/thesis/sensor/p_hit' = -1 is out of range [0, 1]")

    def test_unknown_parameter(self):
        self.check(16, [('scanner/height', '0.45')], "unknown parameter '/bad_sim_node_16/scanner/height' (did you mean "
                   "'scanner/height_m'?): nothing reads it; sim_node reads ", "scanner/max_range_m")

    def test_misspelt_profile_value(self):
        self.check(17, [('profiles/perfect/sensor/p_hti', '1.0')], "unknown parameter '/bad_sim_node_17/profiles/perfect/"
                   "sensor/p_hti' (did you mean 'profiles/perfect/sensor/p_hit'?)")

    def test_unknown_profile(self):
        self.check(7, [('error_profile', 'noisy')], "error profile 'noisy' must be one of perfect, thesis")

    def test_negative_seed(self):
        self.check(8, [('seed', '-5')], "seed' = -5 must be >= 0")

    def test_negative_motion_time_scale(self):
        self.check(9, [('motion_time_scale', '-1.0')], "motion_time_scale' = -1", "out of range [0, 10]")

    def test_start_pose_not_a_number(self):
        self.check(10, [('start_pose', 'a,b,c')], "start_pose' = 'a,b,c'", "is not a number")

    def test_start_pose_in_a_wall(self):
        self.check(11, [('start_pose', '0.0,4.0,0.0')], "start_pose'", "puts the robot")

    def test_equal_frames(self):
        self.check(12, [('odom_frame', 'base_link')], "odom_frame' and", "base_frame' are both 'base_link'")

    def test_missing_materials_file(self):
        self.check(14, [('materials_file', '/nonexistent/room.materials.yaml')], "materials_file' = '/nonexistent/room.materials.yaml'",
                   "/nonexistent/room.materials.yaml: cannot read the materials file")

    def test_mixed_pixel_samples_out_of_range(self):
        self.check(15, [('scanner/mixed_pixels', 'true'), ('scanner/mixed_pixel_samples', '1')],
                   "'scanner/mixed_pixel_samples' = 1 is out of range [2, 8]")

    def test_missing_world(self):
        rc, out = self.run_node(13, [])
        self.assertNotEqual(rc, 0, out)
        self.assertIn("required parameter '/bad_sim_node_13/world' is not set", out)


if __name__ == '__main__':
    rostest.rosrun(PKG, 'sim_bad_parameters', BadParameters, sys.argv)
