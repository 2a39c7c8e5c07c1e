#!/usr/bin/env python3
"""Offline mode: a rosbag of scanner/last_scan and odom played through launch/replay.launch gives
the same map directory poses as the online service (slam/register_scan of an icp_slam_node started
by replay.test in the namespace 'online') fed with the same scans and odometry poses.

The bag is written here: four scans of a synthetic room (walls, a box, floor; base_link frame, a
little noise) taken along a route whose odometry drifts (5 % scale, 2 deg per leg); odometry at
2 Hz, standing still around each scan."""
import csv
import math
import os
import shutil
import signal
import subprocess
import tempfile
import time
import unittest

import numpy as np
import rosbag
import rospy
import rostest
from geometry_msgs.msg import PoseStamped, Quaternion
from nav_msgs.msg import Odometry
from scanstop_msgs.srv import RegisterScan, RegisterScanRequest
from sensor_msgs import point_cloud2
from sensor_msgs.msg import PointCloud2
from std_msgs.msg import Header

TRUTH = [(0.0, 0.0, 0.0), (0.8, 0.3, 0.2), (1.5, -0.4, -0.3), (0.4, 0.9, 1.0)]
SCAN_TIMES = [5.0, 15.0, 25.0, 35.0]


def room(rng, n):
    """Points on three walls, a box and the floor of a 6 x 5 x 2.5 m room (world frame)."""
    a, b = rng.random(n), rng.random(n)
    k = np.arange(n) % 5
    pts = np.zeros((n, 3))
    pts[k == 0] = np.c_[np.full(n, -3.0), 5 * a - 2.5, 2.5 * b][k == 0]        # west wall
    pts[k == 1] = np.c_[6 * a - 3, np.full(n, 2.5), 2.5 * b][k == 1]           # north wall
    pts[k == 2] = np.c_[6 * a - 3, np.full(n, -2.5), 2.5 * b][k == 2]          # south wall
    pts[k == 3] = np.c_[1.0 + 0.5 * a, np.full(n, 0.5), 0.8 * b][k == 3]       # a box face
    pts[k == 4] = np.c_[6 * a - 3, 5 * b - 2.5, np.zeros(n)][k == 4]           # floor
    return pts


def compose(p, q):
    c, s = math.cos(p[2]), math.sin(p[2])
    return (p[0] + c * q[0] - s * q[1], p[1] + s * q[0] + c * q[1], p[2] + q[2])


def between(p, q):
    c, s = math.cos(p[2]), math.sin(p[2])
    dx, dy = q[0] - p[0], q[1] - p[1]
    return (c * dx + s * dy, -s * dx + c * dy, q[2] - p[2])


def quat(yaw):
    return Quaternion(0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))


def odom_msg(pose, t):
    m = Odometry()
    m.header = Header(stamp=rospy.Time.from_sec(t), frame_id="odom")
    m.child_frame_id = "base_link"
    m.pose.pose.position.x, m.pose.pose.position.y = pose[0], pose[1]
    m.pose.pose.orientation = quat(pose[2])
    return m


class ReplayTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="scanstop_replay_test_")

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def test_replay_equals_online(self):
        rng = np.random.default_rng(7)
        world = room(rng, 30000)
        odom = [(0.0, 0.0, 0.0)]
        for i in range(1, len(TRUTH)):
            step = between(TRUTH[i - 1], TRUTH[i])
            odom.append(compose(odom[-1], (step[0] * 1.05, step[1] * 1.05, step[2] + math.radians(2.0))))
        scans = []
        for i, (x, y, yaw) in enumerate(TRUTH):
            c, s = math.cos(yaw), math.sin(yaw)
            R = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
            base = (world - np.array([x, y, 0.0])) @ R  # R^T (p - t) per row
            base += rng.normal(0.0, 0.003, base.shape)
            header = Header(stamp=rospy.Time.from_sec(SCAN_TIMES[i]), frame_id="base_link")
            scans.append(point_cloud2.create_cloud_xyz32(header, base.astype(np.float32).tolist()))

        # The bag: odometry at 2 Hz (still within 3 s of a scan, moving linearly between), the scans.
        bag_path = os.path.join(self.tmp, "run.bag")
        with rosbag.Bag(bag_path, "w") as bag:
            for k in range(0, 2 * 41):
                t = 0.5 * k
                j = max(i for i in range(len(SCAN_TIMES)) if SCAN_TIMES[i] - 5.0 <= t or i == 0)
                if j + 1 < len(SCAN_TIMES) and t > SCAN_TIMES[j] + 3.0:
                    f = min(1.0, (t - SCAN_TIMES[j] - 3.0) / (SCAN_TIMES[j + 1] - SCAN_TIMES[j] - 6.0))
                    p = tuple(odom[j][d] + f * (odom[j + 1][d] - odom[j][d]) for d in range(3))
                else:
                    p = odom[j]
                bag.write("/odom", odom_msg(p, t), rospy.Time.from_sec(t))
            for i, scan in enumerate(scans):
                bag.write("scanner/last_scan", scan, rospy.Time.from_sec(SCAN_TIMES[i] + 0.01))

        # Online: the same scans and odometry poses through the service.
        rospy.wait_for_service("online/slam/register_scan", timeout=30.0)
        register = rospy.ServiceProxy("online/slam/register_scan", RegisterScan)
        online = []
        for i, scan in enumerate(scans):
            req = RegisterScanRequest()
            req.cloud = scan
            req.odom_pose = PoseStamped(header=Header(stamp=scan.header.stamp, frame_id="odom"))
            req.odom_pose.pose.position.x, req.odom_pose.pose.position.y = odom[i][0], odom[i][1]
            req.odom_pose.pose.orientation = quat(odom[i][2])
            res = register(req)
            self.assertTrue(res.success and res.converged, "online scan %d: %s" % (i, res.message))
            q = res.map_pose.pose.orientation
            online.append((res.map_pose.pose.position.x, res.map_pose.pose.position.y,
                           2 * math.atan2(q.z, q.w), res.iterations))

        # slam/map_cloud (grown by each scan): the 5 cm voxels of every scan at its pose, up to 2 m high.
        self.check_map_cloud(scans, online)

        # Offline: replay.launch plays the bag into its own icp_slam_node.
        map_dir = os.path.join(self.tmp, "map")
        poses = os.path.join(map_dir, "poses.csv")
        launch = subprocess.Popen(["roslaunch", "scanstop_slam", "replay.launch", "bag:=" + bag_path,
                                   "map_dir:=" + map_dir, "rate:=4"], start_new_session=True)
        rows = []
        try:
            deadline = time.time() + 90.0
            while time.time() < deadline and len(rows) < len(scans):
                time.sleep(0.5)
                if os.path.exists(poses):
                    with open(poses) as f:
                        rows = list(csv.DictReader(f))
        finally:
            os.killpg(launch.pid, signal.SIGINT)
            try:
                launch.wait(timeout=30)
            except subprocess.TimeoutExpired:
                os.killpg(launch.pid, signal.SIGKILL)
                launch.wait()
        self.assertEqual(len(rows), len(scans), "replay wrote %d of %d scans to %s" % (len(rows), len(scans), poses))
        keys = list(rows[0].keys())
        for i, row in enumerate(rows):
            vals = list(row.values())
            mx, my, myaw = (float(v) for v in vals[3:6])
            ox, oy, oyaw = (float(v) for v in vals[6:9])
            # The odometry pose the node picked from the bag is the one of the scan's stamp.
            self.assertAlmostEqual(ox, odom[i][0], places=6, msg="scan %d odom x (%s)" % (i, keys[6]))
            self.assertAlmostEqual(oy, odom[i][1], places=6, msg="scan %d odom y" % i)
            self.assertAlmostEqual(math.remainder(oyaw - odom[i][2], 2 * math.pi), 0.0, places=6)
            # The result equals the online run's.
            print("scan %d: replay %.6f %.6f %.6f, online %.6f %.6f %.6f, truth %.3f %.3f %.3f"
                  % ((i, mx, my, myaw) + online[i][:3] + TRUTH[i]))
            self.assertAlmostEqual(mx, online[i][0], places=6, msg="scan %d map x" % i)
            self.assertAlmostEqual(my, online[i][1], places=6, msg="scan %d map y" % i)
            self.assertAlmostEqual(math.remainder(myaw - online[i][2], 2 * math.pi), 0.0, places=6)
            self.assertEqual(int(vals[13]), online[i][3], "scan %d iterations" % i)
            # And it is a correction: near the truth where odometry is off.
            self.assertLess(math.hypot(mx - TRUTH[i][0], my - TRUTH[i][1]), 0.01, "scan %d" % i)
        self.assertGreater(math.hypot(odom[3][0] - TRUTH[3][0], odom[3][1] - TRUTH[3][1]), 0.03)  # odometry alone: 4.9 cm off

    def check_map_cloud(self, scans, online):
        got = {}
        sub = rospy.Subscriber("online/slam/map_cloud", PointCloud2, lambda m: got.__setitem__("cloud", m))
        deadline = time.time() + 20.0
        while time.time() < deadline and (
                "cloud" not in got or got["cloud"].header.stamp != scans[-1].header.stamp):
            time.sleep(0.1)
        sub.unregister()
        self.assertIn("cloud", got, "no slam/map_cloud")
        self.assertEqual(got["cloud"].header.stamp, scans[-1].header.stamp, "slam/map_cloud is not of the last scan")
        self.assertEqual(got["cloud"].header.frame_id, "map")
        cloud = np.array(list(point_cloud2.read_points(got["cloud"], field_names=("x", "y", "z"))))
        keys = set(map(tuple, np.floor(cloud / 0.05).astype(np.int64)))
        self.assertEqual(len(keys), len(cloud), "more than one point in a 5 cm voxel")
        self.assertLessEqual(cloud[:, 2].max(), 2.0, "points above map_cloud_max_z_m")
        expected = set()
        for scan, (x, y, yaw, _) in zip(scans, online):
            base = np.array(list(point_cloud2.read_points(scan, field_names=("x", "y", "z"))))
            c, s = math.cos(yaw), math.sin(yaw)
            in_map = base @ np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]]) + np.array([x, y, 0.0])
            in_map = in_map[in_map[:, 2] <= 2.0]
            expected |= set(map(tuple, np.floor(in_map / 0.05).astype(np.int64)))
        differ = len(keys ^ expected)
        print("slam/map_cloud: %d points, %d voxels expected, %d differ" % (len(cloud), len(expected), differ))
        # float (node) against double (here) puts a few points on the other side of a voxel boundary
        self.assertLess(differ, 0.01 * len(expected))


if __name__ == "__main__":
    rospy.init_node("replay_test")
    rostest.rosrun("scanstop_slam", "replay_test", ReplayTest)
