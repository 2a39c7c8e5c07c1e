#!/usr/bin/env python3
"""Bad input to icp_slam_node (issue 9), run by bad_input.test (which starts the node with a map
directory under /tmp):
- slam/register_scan refuses each bad request with success = false and a message saying what was
  wrong, and nothing is applied: slam/path keeps its length, the map directory keeps its scans and
  poses.csv, the next good scan gets the next index;
- the node started with a bad parameter exits non-zero with a FATAL message naming the parameter,
  its value and the allowed range;
- the node started on a map directory with a corrupt and a truncated scan file logs both file names
  and serves with the remaining scans."""
import math
import os
import shutil
import signal
import struct
import subprocess
import time
import unittest

import numpy as np
import roslib.packages
import rospy
import rostest
from geometry_msgs.msg import PoseStamped, Quaternion
from nav_msgs.msg import Path
from scanstop_msgs.srv import RegisterScan, RegisterScanRequest
from sensor_msgs import point_cloud2
from sensor_msgs.msg import PointField
from std_msgs.msg import Header

PKG = 'scanstop_slam'


def room(n=20000, seed=3):
    """Three walls and a box of a 6 x 5 x 2.5 m room, seen from base_link at the origin."""
    rng = np.random.default_rng(seed)
    a, b = rng.random(n), rng.random(n)
    k = np.arange(n) % 4
    pts = np.zeros((n, 3))
    pts[k == 0] = np.c_[np.full(n, -3.0), 5 * a - 2.5, 2.5 * b][k == 0]
    pts[k == 1] = np.c_[6 * a - 3, np.full(n, 2.5), 2.5 * b][k == 1]
    pts[k == 2] = np.c_[6 * a - 3, np.full(n, -2.5), 2.5 * b][k == 2]
    pts[k == 3] = np.c_[1.0 + 0.5 * a, np.full(n, 0.5), 0.8 * b][k == 3]
    return pts


def cloud(pts, frame='base_link'):
    return point_cloud2.create_cloud_xyz32(Header(frame_id=frame, stamp=rospy.Time(1.0)), pts.tolist())


def odom(x=0.0, y=0.0, yaw=0.0, frame='odom'):
    p = PoseStamped()
    p.header.frame_id = frame
    p.pose.position.x, p.pose.position.y = x, y
    p.pose.orientation = Quaternion(0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))
    return p


def node_binary():
    found = roslib.packages.find_node(PKG, 'icp_slam_node')
    if not found:
        raise RuntimeError('icp_slam_node is not built')
    return found[0]


class SlamBadInput(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node('slam_bad_input_test')
        cls.map_dir = rospy.get_param('/icp_slam_node/map_dir')
        cls.path_len = None
        rospy.Subscriber('slam/path', Path, cls.on_path)
        rospy.wait_for_service('slam/register_scan', 30.0)
        cls.register = rospy.ServiceProxy('slam/register_scan', RegisterScan)

    @classmethod
    def on_path(cls, msg):
        cls.path_len = len(msg.poses)

    def wait_path(self, n, timeout=10.0):
        end = time.time() + timeout
        while time.time() < end and self.path_len != n:
            time.sleep(0.05)
        return self.path_len

    def scan_files(self, map_dir=None):
        return sorted(os.listdir(os.path.join(map_dir or self.map_dir, 'scans')))

    def bad_requests(self):
        """(what, request, text the message must contain)."""
        good = room(2000)
        out = []

        def add(what, c, o, text):
            out.append((what, RegisterScanRequest(cloud=c, odom_pose=o), text))

        add('cloud in the map frame', cloud(good, 'map'), odom(0.1), "the cloud is in frame 'map', expected 'base_link'")
        add('odom_pose in base_link', cloud(good), odom(0.1, frame='base_link'),
            "odom_pose is in frame 'base_link', expected 'odom'")
        add('empty cloud', cloud(np.zeros((0, 3))), odom(0.1), 'the cloud is empty')
        c = cloud(good)
        c.fields = [f for f in c.fields if f.name != 'z']
        add('no z field', c, odom(0.1), "no 'z' field")
        c = cloud(good)
        c.fields[0].datatype = PointField.FLOAT64
        add('float64 x', c, odom(0.1), "field 'x' has datatype 8, expected float32")
        c = cloud(good)
        c.fields[2].datatype = PointField.UINT16
        add('uint16 z', c, odom(0.1), "field 'z' has datatype 4")
        c = cloud(good)
        c.point_step = 8
        add('point_step too small', c, odom(0.1), 'outside point_step 8')
        c = cloud(good)
        c.data = c.data[:-7]
        add('truncated data', c, odom(0.1), 'needs')
        c = cloud(good)
        c.height = 3
        add('height larger than the data', c, odom(0.1), 'needs')
        nan = good.copy()
        nan[:] = float('nan')
        add('all points NaN', cloud(nan), odom(0.1), 'no finite point')
        inf = good.copy()
        inf[17] = (1.0, float('inf'), 0.0)
        add('infinite point', cloud(inf), odom(0.1), 'point 17')
        far = good.copy()
        far[5] = (0.0, 1.0e6, 0.0)
        add('point 1000 km away', cloud(far), odom(0.1), 'max_point_distance')
        add('NaN odometry position', cloud(good), odom(float('nan')), 'odom_pose.position')
        o = odom(0.1)
        o.pose.orientation = Quaternion(0.0, 0.0, 0.3, 0.5)
        add('non-normalized quaternion', cloud(good), o, 'not a unit quaternion')
        o = odom(0.1)
        o.pose.orientation = Quaternion(0.0, 0.0, 0.0, 0.0)
        add('zero quaternion', cloud(good), o, 'not a unit quaternion')
        add('100 m forward move', cloud(good), odom(100.0), 'max_odom_jump')
        return out

    def test_1_bad_requests_change_nothing(self):
        r = self.register(RegisterScanRequest(cloud=cloud(room()), odom_pose=odom()))
        self.assertTrue(r.success, r.message)
        self.assertEqual(r.scan_index, 0)
        self.assertEqual(self.wait_path(1), 1)
        poses = open(os.path.join(self.map_dir, 'poses.csv')).read()
        for what, req, text in self.bad_requests():
            r = self.register(req)
            self.assertFalse(r.success, 'accepted: ' + what)
            self.assertIn(text, r.message, what)
            self.assertTrue(r.message.startswith('bad request: '), r.message)
        time.sleep(0.5)
        self.assertEqual(self.path_len, 1, 'slam/path grew')
        self.assertEqual(self.scan_files(), ['scan_0000.pcd'])
        self.assertEqual(open(os.path.join(self.map_dir, 'poses.csv')).read(), poses)
        r = self.register(RegisterScanRequest(cloud=cloud(room(seed=4)), odom_pose=odom(0.05)))
        self.assertTrue(r.success, r.message)
        self.assertEqual(r.scan_index, 1)
        self.assertTrue(r.converged, r.message)
        self.assertEqual(self.wait_path(2), 2)

    def run_node(self, name, params, timeout=30):
        args = [node_binary(), '__name:=' + name] + ['_%s:=%s' % kv for kv in params]
        proc = subprocess.run(args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=timeout,
                              universal_newlines=True)
        return proc.returncode, proc.stdout

    def check_bad_param(self, index, params, *expected):
        rc, out = self.run_node('bad_slam_%d' % index, params)
        self.assertNotEqual(rc, 0, 'icp_slam_node with %s exited 0:\n%s' % (params, out))
        self.assertIn('FATAL', out, out)
        for text in expected:
            self.assertIn(text, out, 'expected %r for %s:\n%s' % (text, params, out))

    def test_2_bad_parameters_stop_the_node(self):
        self.check_bad_param(1, [('c_max_m', '-0.1')], "'c_max_m' = -0.1 m is out of range [0.001, 5 m]")
        self.check_bad_param(2, [('max_iterations', '0')], "'max_iterations' = 0 is out of range [1, 10000]")
        self.check_bad_param(3, [('min_overlap', '1.5')], "'min_overlap' = 1.5 is out of range [0, 1]")
        self.check_bad_param(4, [('max_odom_jump_m', '-5')], "'max_odom_jump_m' = -5 m is out of range [0.01, 100000 m]")
        self.check_bad_param(5, [('max_point_distance_m', '0.0')],
                             "'max_point_distance_m' = 0 m is out of range [0.1, 10000 m]")
        self.check_bad_param(6, [('r_c_deg', '90')], "'/bad_slam_6/r_c_deg' = 90 deg is out of range [1e-07, 45 deg]")
        self.check_bad_param(7, [('sensor_height_m', '50')], "'sensor_height_m' = 50 m is out of range [-10, 10 m]")
        self.check_bad_param(8, [('mode', '4dof')], "'/bad_slam_8/mode' = '4dof' must be 3dof or 6dof")
        self.check_bad_param(9, [('map_frame', 'odom')], "map_frame' and", "odom_frame' are both 'odom'")
        self.check_bad_param(10, [('base_frame', '')], "'/bad_slam_10/base_frame' = ''")
        self.check_bad_param(11, [('c_max_m', 'wide')], "parameter '/bad_slam_11/c_max_m' has the wrong type")
        self.check_bad_param(12, [('max_cloud_points', '0')], "'max_cloud_points' = 0 is out of range [1, 1e+08]")
        # The name before its unit was in it: refused, with the new name.
        self.check_bad_param(13, [('c_max', '0.5')], "unknown parameter '/bad_slam_13/c_max' (did you mean 'c_max_m'?): "
                             "nothing reads it; icp_slam_node reads ", "refine_r_c_deg")

    def test_3_corrupt_scan_files_are_skipped_by_name(self):
        # A copy of the map directory (the launched node keeps writing its own) with four scans.
        resumed_dir = self.map_dir + '_resumed'
        proc = None
        try:
            shutil.rmtree(resumed_dir, ignore_errors=True)
            os.makedirs(os.path.join(resumed_dir, 'scans'))
            for i in range(4):
                r = self.register(RegisterScanRequest(cloud=cloud(room(seed=10 + i)), odom_pose=odom(0.05 + 0.01 * i)))
                self.assertTrue(r.success, r.message)
            for f in os.listdir(os.path.join(self.map_dir, 'scans')):
                shutil.copy(os.path.join(self.map_dir, 'scans', f), os.path.join(resumed_dir, 'scans', f))
            shutil.copy(os.path.join(self.map_dir, 'poses.csv'), os.path.join(resumed_dir, 'poses.csv'))
            n = len(self.scan_files(resumed_dir))
            self.assertGreaterEqual(n, 5)
            with open(os.path.join(resumed_dir, 'scans', 'scan_0001.pcd'), 'w') as f:
                f.write('# not a PCD file\ngarbage\n')
            p2 = os.path.join(resumed_dir, 'scans', 'scan_0002.pcd')
            data = open(p2, 'rb').read()
            open(p2, 'wb').write(data[:len(data) // 3])
            log = os.path.join(resumed_dir, 'node.log')
            with open(log, 'w') as out:
                proc = subprocess.Popen([node_binary(), '__name:=resumed_slam', '__ns:=resumed',
                                         '_map_dir:=' + resumed_dir], stdout=out, stderr=subprocess.STDOUT)
            rospy.wait_for_service('/resumed/slam/register_scan', 30.0)
            self.assertIsNone(proc.poll(), 'the node exited')
            register = rospy.ServiceProxy('/resumed/slam/register_scan', RegisterScan)
            r = register(RegisterScanRequest(cloud=cloud(room(seed=30)), odom_pose=odom(0.1)))
            self.assertTrue(r.success, r.message)
            self.assertTrue(r.converged, r.message)
            self.assertEqual(r.scan_index, n)
            proc.send_signal(signal.SIGINT)  # its stdout (INFO) is block-buffered into the file until it exits
            proc.wait(15)
            text = open(log).read()
            for f in ('scan_0001.pcd', 'scan_0002.pcd'):
                self.assertIn('map directory problem, skipped: ' + os.path.join(resumed_dir, 'scans', f), text, text)
            self.assertIn('with %d scans (2 skipped' % n, text, text)
            self.assertLess(abs(r.map_pose.pose.position.x), 0.02)  # the room is where the kept scans put it
        finally:
            if proc is not None and proc.poll() is None:
                proc.send_signal(signal.SIGINT)
                try:
                    proc.wait(10)
                except subprocess.TimeoutExpired:
                    proc.kill()
            shutil.rmtree(resumed_dir, ignore_errors=True)

    @classmethod
    def tearDownClass(cls):
        if cls.map_dir.startswith('/tmp/'):
            shutil.rmtree(cls.map_dir, ignore_errors=True)


if __name__ == '__main__':
    rostest.rosrun(PKG, 'slam_bad_input', SlamBadInput)
