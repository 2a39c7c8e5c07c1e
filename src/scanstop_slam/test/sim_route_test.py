#!/usr/bin/env python3
"""ICP SLAM against sim_node on a fixed 15-scan route through room_10x8 (issue 4, accuracy in
simulation), run by sim_route.test: thesis error profile, a fixed seed, the node's defaults.

The route is 15 scan positions around the furniture of the room (world coordinates of
worlds/room_10x8.stl; the map frame starts at the world's start pose (2, 5, 0)). The test drives it
as the mission does, closed loop: after each registration it turns towards the next position and
drives straight there, computing the motion from the corrected (SLAM) pose; sim_node executes it
with the thesis' motion errors. At the end it compares the SLAM pose of the last scan and the
odometry pose with the ground truth: the SLAM pose must be within ~max_error_m and ~max_error_deg,
while the odometry alone is off by much more. Both errors are printed for every scan. ~truth_file
receives the true pose of every scan (as mission_state.yaml holds them) for
`icp_replay MAP_DIR --truth FILE`.

The bounds in sim_route.test are the issue's target, 2 cm and 0.3 deg. The route ends at 0.3 cm and
0.12 deg (up to 5.1 cm on the way: from (6, 3) the east and west walls are 4 and 6 m away, at the
URG's 5.6 m limit, and the map of the first three scans holds x only weakly); before IcpSlam's
refinement stage (unique matches, tight tolerances) it ended at 2.6 cm and 0.44 deg."""
import math
import sys
import unittest

import rospy
import rostest
from nav_msgs.msg import Odometry
from scanstop_msgs.srv import Forward, RegisterScan, Rotate, TakeScan

PKG = 'scanstop_slam'
START = (2.0, 5.0)  # the world's start pose (yaw 0): the origin of the map and odom frames
ROUTE_WORLD = [(2.0, 5.0), (3.5, 4.0), (4.5, 3.0), (6.0, 3.0), (7.5, 3.0), (8.5, 2.0), (8.5, 4.0), (8.0, 5.5),
               (7.5, 7.0), (6.0, 7.0), (4.5, 7.0), (3.0, 6.5), (1.5, 6.0), (1.5, 4.0), (1.0, 3.0)]


def yaw_of(q):
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def wrap(a):
    return math.atan2(math.sin(a), math.cos(a))


def pose2d(p):
    return p.position.x, p.position.y, yaw_of(p.orientation)


class SimRoute(unittest.TestCase):
    def test_route(self):
        rospy.init_node('sim_route_test')
        planes = rospy.get_param('~planes', 400)
        max_err_m = rospy.get_param('~max_error_m', 0.02)
        max_err_deg = rospy.get_param('~max_error_deg', 0.3)
        # Every scan of the route, not only the last (the ATE): 0 = not checked.
        max_route_err_m = rospy.get_param('~max_route_error_m', 0.0)
        max_route_err_deg = rospy.get_param('~max_route_error_deg', 0.0)
        worst = (0.0, 0.0, 0, 0)  # position error, yaw error and their scans
        self.truth = None
        rospy.Subscriber('ground_truth', Odometry, self.on_truth)
        for name in ('scanner/take_scan', 'slam/register_scan', 'base/rotate', 'base/forward'):
            rospy.wait_for_service(name, timeout=60)
        take = rospy.ServiceProxy('scanner/take_scan', TakeScan)
        register = rospy.ServiceProxy('slam/register_scan', RegisterScan)
        rotate = rospy.ServiceProxy('base/rotate', Rotate)
        forward = rospy.ServiceProxy('base/forward', Forward)
        route = [(x - START[0], y - START[1]) for x, y in ROUTE_WORLD]
        self.assertEqual(len(route), 15)
        truth_file = rospy.get_param('~truth_file', '')
        truths = []
        print('scan  slam error (cm, deg)   odometry error (cm, deg)   iterations  time (s)')
        for i, target in enumerate(route):
            if i > 0:  # drive from the corrected pose of the last scan to the next position
                x, y, yaw = slam
                dx, dy = target[0] - x, target[1] - y
                r = rotate(wrap(math.atan2(dy, dx) - yaw))
                self.assertTrue(r.success and not r.collision, 'rotate before scan %d: %s' % (i, r.message))
                f = forward(math.hypot(dx, dy))
                self.assertTrue(f.success and not f.collision, 'forward to scan %d: %s' % (i, f.message))
            scan = take(planes)
            self.assertTrue(scan.success, 'scan %d: %s' % (i, scan.message))
            reg = register(scan.cloud, scan.odom_pose)
            self.assertTrue(reg.success, 'registration of scan %d: %s' % (i, reg.message))
            self.assertTrue(reg.converged, 'registration of scan %d did not converge: %s' % (i, reg.message))
            slam = pose2d(reg.map_pose.pose)
            odom = pose2d(scan.odom_pose.pose)
            truth = self.current_truth()
            truths.append(truth)
            if truth_file:  # for offline replays: icp_replay MAP_DIR --truth FILE
                with open(truth_file, 'w') as f:
                    f.write('scans:\n' + ''.join('  - {index: %d, true_pose: [%.6f, %.6f, %.6f]}\n' % ((k,) + t)
                                                  for k, t in enumerate(truths)))
            slam_err = (math.hypot(slam[0] - truth[0], slam[1] - truth[1]), abs(math.degrees(wrap(slam[2] - truth[2]))))
            odom_err = (math.hypot(odom[0] - truth[0], odom[1] - truth[1]), abs(math.degrees(wrap(odom[2] - truth[2]))))
            print('%4d  %8.2f %8.3f        %8.2f %8.3f           %4d      %6.2f' % (
                i, 100 * slam_err[0], slam_err[1], 100 * odom_err[0], odom_err[1], reg.iterations, reg.duration_s))
            sys.stdout.flush()
            worst = (max(worst[0], slam_err[0]), max(worst[1], slam_err[1]),
                     i if slam_err[0] > worst[0] else worst[2], i if slam_err[1] > worst[1] else worst[3])
        print('largest SLAM error on the route: %.2f cm (scan %d), %.3f deg (scan %d)' % (
            100 * worst[0], worst[2], worst[1], worst[3]))
        if max_route_err_m > 0:
            self.assertLessEqual(worst[0], max_route_err_m, 'SLAM position error %.1f cm at scan %d' % (
                100 * worst[0], worst[2]))
        if max_route_err_deg > 0:
            self.assertLessEqual(worst[1], max_route_err_deg, 'SLAM yaw error %.2f deg at scan %d' % (worst[1], worst[3]))
        self.assertLessEqual(slam_err[0], max_err_m, 'final SLAM position error %.1f cm' % (100 * slam_err[0]))
        self.assertLessEqual(slam_err[1], max_err_deg, 'final SLAM yaw error %.2f deg' % slam_err[1])
        # Odometry alone drifts far more on the same route (the point of the SLAM).
        self.assertGreater(odom_err[0], 5 * max(slam_err[0], 0.01), 'odometry error %.1f cm' % (100 * odom_err[0]))

    def on_truth(self, msg):
        self.truth = pose2d(msg.pose.pose)

    def current_truth(self):
        # The robot stands still from the scan to here; the latched truth is that of the scan.
        deadline = rospy.get_time() + 10.0
        while self.truth is None and rospy.get_time() < deadline:
            rospy.sleep(0.05)
        self.assertIsNotNone(self.truth, 'no ground_truth from sim_node')
        return self.truth


if __name__ == '__main__':
    rostest.rosrun(PKG, 'sim_route', SimRoute, sys.argv)
