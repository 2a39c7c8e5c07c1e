#!/usr/bin/env python3
"""Starts rotating_urg_driver with one bad parameter at a time: it must exit non-zero at once with a
FATAL message naming the parameter, its value and the allowed range (issue 9). Run by
bad_param.test (the rostest provides the master). No device is needed: parameters are checked first."""
import subprocess
import sys
import unittest

import roslib.packages
import rostest

PKG = 'scanstop_urg'


class BadParameters(unittest.TestCase):
    def run_node(self, index, params):
        found = roslib.packages.find_node(PKG, 'rotating_urg_driver')
        self.assertTrue(found, 'rotating_urg_driver is not built')
        args = [found[0], '__name:=bad_urg_%d' % index] + ['_%s:=%s' % kv for kv in params]
        proc = subprocess.run(args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=60,
                              universal_newlines=True)
        return proc.returncode, proc.stdout

    def check(self, index, params, *expected):
        rc, out = self.run_node(index, params)
        self.assertNotEqual(rc, 0, 'rotating_urg_driver with %s kept running or exited 0:\n%s' % (params, out))
        self.assertIn('FATAL', out, out)
        for text in expected:
            self.assertIn(text, out, 'expected %r in the output for %s:\n%s' % (text, params, out))

    def test_scanner_height(self):
        self.check(1, [('scanner/height_m', '7.0')], "'scanner/height_m' = 7 m is out of range [0.05, 3 m]")

    def test_baud(self):
        self.check(2, [('baud', '12345')], "'baud' = 12345 is not a supported rate")

    def test_negative_reply_timeout(self):
        self.check(3, [('reply_timeout_s', '-1.0')], "'reply_timeout_s' = -1 s is out of range [0.001, 60 s]")

    def test_negative_standstill_threshold(self):
        self.check(4, [('standstill/max_linear_speed_mps', '-0.1')],
                   "'standstill/max_linear_speed_mps' = -0.1 m/s is out of range [0, 0.5 m/s]")

    def test_odom_timeout(self):
        self.check(5, [('odom_timeout_s', '100.0')], "odom_timeout_s' = 100 s is out of range [0, 60 s]")

    def test_platform_type(self):
        self.check(6, [('platform/type', 'servo')], "platform/type' = 'servo': only 'stepper' is implemented")

    def test_equal_frames(self):
        self.check(7, [('laser_frame', 'base_link')], "base_frame' and", "laser_frame' are both 'base_link'")

    def test_platform_retries(self):
        self.check(8, [('platform/retries', '50')], "'platform/retries' = 50 is out of range [0, 20]")

    def test_plane_retries(self):
        self.check(9, [('max_plane_retries', '50')], "max_plane_retries = 50 must be in 0..20")

    def test_unknown_parameter(self):
        self.check(11, [('scanner/height', '0.45')], "unknown parameter '/bad_urg_11/scanner/height' (did you mean "
                   "'scanner/height_m'?): nothing reads it; rotating_urg_driver reads ", "scanner/max_range_m")

    def test_wrong_type(self):
        self.check(10, [('scanner/height_m', 'high')], "parameter '/bad_urg_10/scanner/height_m' has the wrong type")


if __name__ == '__main__':
    rostest.rosrun(PKG, 'urg_bad_parameters', BadParameters, sys.argv)
