#!/usr/bin/env python3
"""Starts pioneer_driver with one bad parameter at a time: it must exit non-zero at once with a
FATAL message naming the parameter, its value and the allowed range (issue 9). Run by
bad_param.test (the rostest provides the master). No robot is needed: parameters are checked first."""
import subprocess
import sys
import unittest

import roslib.packages
import rostest

PKG = 'scanstop_pioneer'


class BadParameters(unittest.TestCase):
    def run_node(self, index, params):
        found = roslib.packages.find_node(PKG, 'pioneer_driver')
        self.assertTrue(found, 'pioneer_driver is not built')
        args = [found[0], '__name:=bad_pioneer_%d' % index] + ['_%s:=%s' % kv for kv in params]
        proc = subprocess.run(args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=60,
                              universal_newlines=True)
        return proc.returncode, proc.stdout

    def check(self, index, params, *expected):
        rc, out = self.run_node(index, [('port', '/dev/null')] + params)
        self.assertNotEqual(rc, 0, 'pioneer_driver with %s kept running or exited 0:\n%s' % (params, out))
        self.assertIn('FATAL', out, out)
        for text in expected:
            self.assertIn(text, out, 'expected %r in the output for %s:\n%s' % (text, params, out))

    def test_negative_speed(self):
        self.check(1, [('motion/linear_speed_mps', '-1.0')], "'motion/linear_speed_mps' = -1 m/s is out of range [0.01, 1.5 m/s]")

    def test_speed_above_the_bound(self):
        self.check(2, [('motion/linear_speed_mps', '0.8')], "'motion/linear_speed_mps' = 0.8 m/s is out of range [0.01, 0.5 m/s]")

    def test_absurd_max_forward(self):
        self.check(3, [('motion/max_forward_m', '1000.0')], "'motion/max_forward_m' = 1000 m is out of range [0.01, 100 m]")

    def test_absurd_max_rotate(self):
        self.check(4, [('motion/max_rotate_rad', '50.0')], "'motion/max_rotate_rad' = 50 rad is out of range")

    def test_negative_cmd_vel_timeout(self):
        self.check(5, [('cmd_vel_timeout_s', '-1.0')], "'cmd_vel_timeout_s' = -1 s is out of range [0.05, 10 s]")

    def test_pulse_beyond_the_watchdog(self):
        self.check(6, [('pulse_period_s', '3.0')], "'pulse_period_s' = 3 s is out of range [0.05, 1.5 s]")

    def test_baud(self):
        self.check(7, [('baud', '12345')], "'baud' = 12345 must be one of 9600, 19200")

    def test_equal_frames(self):
        self.check(8, [('odom_frame', 'base_link')], "odom_frame' and", "base_frame' are both 'base_link'")

    def test_missing_port(self):
        rc, out = self.run_node(9, [])
        self.assertNotEqual(rc, 0, out)
        self.assertIn("required parameter '/bad_pioneer_9/port' is not set", out)

    def test_unknown_parameter(self):
        self.check(11, [('motion/linear_speed', '0.1')], "unknown parameter '/bad_pioneer_11/motion/linear_speed' (did you "
                   "mean 'motion/linear_speed_mps'?): nothing reads it; pioneer_driver reads ", "motion/max_forward_m")

    def test_wrong_type(self):
        self.check(10, [('sip_timeout_s', 'long')], "parameter '/bad_pioneer_10/sip_timeout_s' has the wrong type")


if __name__ == '__main__':
    rostest.rosrun(PKG, 'pioneer_bad_parameters', BadParameters, sys.argv)
