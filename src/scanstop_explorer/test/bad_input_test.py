#!/usr/bin/env python3
"""Bad input to explorer_node (issue 9), run by bad_input.test:
- explorer/plan_next refuses each bad request with success = false and a message saying what was
  wrong, and applies nothing: no step files are written, an unreachable list holding the last
  target next to a bad point does not blacklist it (the next plan picks the same target), a
  registered scan with an absurd point does not enter the floor map;
- explorer_node started with a bad parameter exits non-zero with a FATAL message naming the
  parameter, its value and the allowed range."""
import math
import os
import shutil
import subprocess
import time
import unittest

import numpy as np
import roslib.packages
import rospy
import rostest
from geometry_msgs.msg import Point, PoseStamped, Quaternion
from scanstop_msgs.msg import RegisteredScan
from scanstop_msgs.srv import PlanNext, PlanNextRequest
from sensor_msgs import point_cloud2
from std_msgs.msg import Header

PKG = 'scanstop_explorer'


def room_scan(x, y, seed=1):
    """Floor, walls and a box of an 8 x 4 m room (map frame) seen within 3 m of (x, y)."""
    rng = np.random.default_rng(seed)
    pts = []
    for gx in np.arange(0.05, 8.0, 0.05):
        for gy in np.arange(0.05, 4.0, 0.05):
            if math.hypot(gx - x, gy - y) < 3.0 and not (3.0 < gx < 3.6 and 1.0 < gy < 2.0):
                pts.append((gx, gy, 0.0))
    for z in np.arange(0.0, 1.0, 0.1):
        for t in np.arange(0.0, 8.0, 0.05):
            pts += [(t, 0.0, z), (t, 4.0, z)]
        for t in np.arange(0.0, 4.0, 0.05):
            pts += [(0.0, t, z), (8.0, t, z)]
        for t in np.arange(0.0, 0.6, 0.05):
            pts += [(3.0 + t, 1.0, z), (3.0 + t, 2.0, z)]
        for t in np.arange(0.0, 1.0, 0.05):
            pts += [(3.0, 1.0 + t, z), (3.6, 1.0 + t, z)]
    pts = [p for p in pts if math.hypot(p[0] - x, p[1] - y) < 3.0]
    return np.array(pts) + rng.normal(0.0, 0.002, (len(pts), 3))


def pose(x, y, yaw=0.0, frame='map'):
    p = PoseStamped()
    p.header.frame_id = frame
    p.pose.position.x, p.pose.position.y = x, y
    p.pose.orientation = Quaternion(0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))
    return p


def scan_msg(index, x, y, pts):
    m = RegisteredScan()
    m.header = Header(frame_id='map', stamp=rospy.Time.now())
    m.scan_index = index
    m.pose = pose(x, y)
    m.sensor_origin.x, m.sensor_origin.y, m.sensor_origin.z = x, y, 0.45
    m.cloud = point_cloud2.create_cloud_xyz32(m.header, pts.tolist())
    m.registration_ok = True
    return m


def node_binary():
    found = roslib.packages.find_node(PKG, 'explorer_node')
    if not found:
        raise RuntimeError('explorer_node is not built')
    return found[0]


class ExplorerBadInput(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node('explorer_bad_input_test')
        cls.run_dir = rospy.get_param('/explorer_node/run_dir')
        rospy.wait_for_service('explorer/plan_next', 30.0)
        cls.plan = rospy.ServiceProxy('explorer/plan_next', PlanNext)
        cls.pub = rospy.Publisher('slam/registered_scan', RegisteredScan, queue_size=10, latch=True)

    def step_files(self):
        return sorted(f for f in os.listdir(self.run_dir) if f.startswith('step_'))

    def test_1_bad_requests_change_nothing(self):
        self.pub.publish(scan_msg(0, 1.5, 2.0, room_scan(1.5, 2.0)))
        first = None
        for _ in range(100):
            first = self.plan(PlanNextRequest(map_pose=pose(1.5, 2.0)))
            if first.success:
                break
            time.sleep(0.1)
        self.assertTrue(first.success, first.message)
        self.assertFalse(first.exploration_complete, first.complete_reason)
        target = first.target.pose.position
        files = self.step_files()
        self.assertTrue(any(f.startswith('step_001_') for f in files), files)

        nan = float('nan')
        q = pose(1.5, 2.0)
        q.pose.orientation = Quaternion(0.0, 0.0, 0.0, 2.0)
        zero = pose(1.5, 2.0)
        zero.pose.orientation = Quaternion(0.0, 0.0, 0.0, 0.0)
        bad = [
            ('map_pose in odom', PlanNextRequest(map_pose=pose(1.5, 2.0, frame='odom')),
             "map_pose is in frame 'odom', expected 'map'"),
            ('NaN position', PlanNextRequest(map_pose=pose(nan, 2.0)), 'map_pose.position'),
            ('non-normalized quaternion', PlanNextRequest(map_pose=q), 'not a unit quaternion'),
            ('zero quaternion', PlanNextRequest(map_pose=zero), 'not a unit quaternion (norm 0)'),
            ('robot 50 km away', PlanNextRequest(map_pose=pose(5.0e4, 2.0)), 'beyond max_coordinate_m'),
            ('the last target next to a NaN point',
             PlanNextRequest(map_pose=pose(1.5, 2.0), unreachable=[Point(target.x, target.y, 0.0), Point(nan, 0, 0)]),
             'unreachable[1]'),
            ('an absurd unreachable point',
             PlanNextRequest(map_pose=pose(1.5, 2.0), unreachable=[Point(target.x, target.y, 0.0), Point(0, 1e9, 0)]),
             'unreachable[1] (0, 1e+09) is beyond max_coordinate_m'),
            ('too many unreachable points',
             PlanNextRequest(map_pose=pose(1.5, 2.0), unreachable=[Point(target.x, target.y, 0.0)] * 10001),
             'more than max_unreachable'),
            ('contact radii that do not match the contacts',
             PlanNextRequest(map_pose=pose(1.5, 2.0), contacts=[Point(0.5, 0.5, 0.0)], contact_radii=[0.05, 0.05]),
             'contact_radii has 2 values for 1 contacts'),
            ('a negative contact radius',
             PlanNextRequest(map_pose=pose(1.5, 2.0), contacts=[Point(0.5, 0.5, 0.0)], contact_radii=[-0.1]),
             'contact_radii[0] -0.1 m is not in [0, 2]'),
        ]
        for what, req, text in bad:
            r = self.plan(req)
            self.assertFalse(r.success, 'accepted: ' + what)
            self.assertIn(text, r.message, what)
            self.assertTrue(r.message.startswith('bad request: '), r.message)
        self.assertEqual(self.step_files(), files, 'a refused request wrote step files')

        # A registered scan with a point 1 km away is dropped: the floor stays as it was.
        far = room_scan(6.0, 2.0)
        far[10] = (1000.0, 2.0, 0.0)
        self.pub.publish(scan_msg(1, 6.0, 2.0, far))
        time.sleep(1.0)

        second = self.plan(PlanNextRequest(map_pose=pose(1.5, 2.0)))
        self.assertTrue(second.success, second.message)
        self.assertAlmostEqual(second.target.pose.position.x, target.x, places=6)
        self.assertAlmostEqual(second.target.pose.position.y, target.y, places=6)
        self.assertAlmostEqual(second.floor_area_m2, first.floor_area_m2, places=6)
        self.assertTrue(any(f.startswith('step_002_') for f in self.step_files()))

    def check_bad_param(self, index, params, *expected):
        args = [node_binary(), '__name:=bad_explorer_%d' % index] + ['_%s:=%s' % kv for kv in params]
        proc = subprocess.run(args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=30,
                              universal_newlines=True)
        self.assertNotEqual(proc.returncode, 0, 'explorer_node with %s exited 0:\n%s' % (params, proc.stdout))
        self.assertIn('FATAL', proc.stdout, proc.stdout)
        for text in expected:
            self.assertIn(text, proc.stdout, 'expected %r for %s:\n%s' % (text, params, proc.stdout))

    def test_2_bad_parameters_stop_the_node(self):
        self.check_bad_param(1, [('resolution_m', '0.0')], "'resolution_m' = 0 m is out of range")
        self.check_bad_param(2, [('d_max_m', '-2')], "'d_max_m' = -2 m is out of range [1e-06, 50 m]")
        self.check_bad_param(3, [('k_r_m', '500')], "'k_r_m' = 500 m is out of range [1e-06, 50 m]")
        self.check_bad_param(4, [('robot_radius_m', 'nan')], "'robot_radius_m' = nan m is out of range")
        self.check_bad_param(5, [('max_failed_attempts', '0')], "'max_failed_attempts' = 0 is out of range [1, 100]")
        self.check_bad_param(6, [('image_scale', '64')], "'/bad_explorer_6/image_scale' = 64 is out of range [1, 16]")
        self.check_bad_param(7, [('max_coordinate_m', '0.5')],
                             "'/bad_explorer_7/max_coordinate_m' = 0.5 m is out of range [1, 1e+06 m]")
        self.check_bad_param(8, [('frame_id', '/map')], "'/bad_explorer_8/frame_id' = '/map'")
        self.check_bad_param(9, [('d_max_m', 'far')], "parameter '/bad_explorer_9/d_max_m' has the wrong type")
        self.check_bad_param(10, [('k_r', '2.5')], "unknown parameter '/bad_explorer_10/k_r' (did you mean 'k_r_m'?): "
                             "nothing reads it; explorer_node reads ", "d_max_m")

    @classmethod
    def tearDownClass(cls):
        if cls.run_dir.startswith('/tmp/'):
            shutil.rmtree(cls.run_dir, ignore_errors=True)


if __name__ == '__main__':
    rostest.rosrun(PKG, 'explorer_bad_input', ExplorerBadInput)
