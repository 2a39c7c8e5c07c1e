#!/usr/bin/env python3
"""Two hosts on one machine: two network namespaces joined by a veth pair.

"robot" (10.47.0.1) runs the ROS master, sim_node and mission_node (launch/two_host_robot.launch);
"workstation" (10.47.0.2) runs icp_slam_node, explorer_node and bpa_mesher_node
(launch/two_host_workstation.launch). A short exploration of room_10x8 (50 planes, 4 scans) runs
over the plain link, then again with `tc netem delay 50ms 10ms loss 2%` on both ends of the link
(where the kernel has no sch_netem, the same impairment from a user-space link: link_emulator.py);
both must end DONE with every scan kept exactly once (the mission's scans equal the workstation's
map, index by index and pose by pose), and the lossy run must be the slower one.

Needs root (CAP_NET_ADMIN, CAP_SYS_ADMIN for `ip netns`): without it the test fails and says so.
The namespaces and the link are removed at the end, on failure and on SIGTERM too.
"""
import atexit
import csv
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import unittest

import rospkg
import yaml

PKG = "scanstop_mission"
BUDGET = 4
ROBOT_IP, WS_IP = "10.47.0.1", "10.47.0.2"
PORT = 11311
TIMEOUT_S = 150  # per run


def sh(*args, check=True):
    r = subprocess.run(list(args), stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True)
    if check and r.returncode != 0:
        raise RuntimeError("%s failed (exit %d): %s" % (" ".join(args), r.returncode, r.stdout.strip()))
    return r


class Link(object):
    """Two network namespaces joined by a veth pair; removed by close() (also at exit)."""

    def __init__(self):
        tag = str(os.getpid())
        self.robot, self.ws = "ssrob%s" % tag, "ssws%s" % tag
        self.robot_if, self.ws_if = "ssr%s" % tag[-8:], "ssw%s" % tag[-8:]
        self.closed = False
        self.emulator = None
        atexit.register(self.close)
        r = sh("ip", "netns", "add", self.robot, check=False)
        if r.returncode != 0:
            raise PermissionError(
                "TWO-HOST TEST CANNOT RUN: `ip netns add` failed (%s). It needs root with CAP_NET_ADMIN and "
                "CAP_SYS_ADMIN (the CI runs as root). This is a failure, not a skip." % r.stdout.strip())
        sh("ip", "netns", "add", self.ws)
        sh("ip", "link", "add", self.robot_if, "type", "veth", "peer", "name", self.ws_if)
        for ns, ifname, ip in ((self.robot, self.robot_if, ROBOT_IP), (self.ws, self.ws_if, WS_IP)):
            sh("ip", "link", "set", ifname, "netns", ns)
            sh("ip", "-n", ns, "addr", "add", ip + "/24", "dev", ifname)
            sh("ip", "-n", ns, "link", "set", ifname, "up")
            sh("ip", "-n", ns, "link", "set", "lo", "up")

    def impair(self, delay_ms, jitter_ms, loss):
        """Delay (uniform jitter) and loss on both ends: `tc netem` on the veth pair; on a kernel built
        without sch_netem, the veth pair is replaced by a user-space link with the same addresses
        and the same impairment (test/link_emulator.py). Returns a description of what was used."""
        spec = "delay %gms %gms loss %g%%" % (delay_ms, jitter_ms, loss * 100)
        r = sh("ip", "netns", "exec", self.robot, "tc", "qdisc", "add", "dev", self.robot_if, "root", "netem",
               *spec.split(), check=False)
        if r.returncode == 0:
            sh("ip", "netns", "exec", self.ws, "tc", "qdisc", "add", "dev", self.ws_if, "root", "netem", *spec.split())
            return "tc netem %s on both ends of the veth pair" % spec
        if "qdisc kind is unknown" not in r.stdout:
            raise RuntimeError("tc netem failed: %s" % r.stdout.strip())
        print("*** this kernel has no sch_netem (tc: %s): emulating `netem %s` on both ends with a user-space "
              "link (test/link_emulator.py, TUN devices) instead of the veth pair ***" % (r.stdout.strip(), spec))
        sh("ip", "-n", self.robot, "link", "del", self.robot_if)  # removes both ends
        self.emulator = subprocess.Popen(
            [sys.executable, os.path.join(os.path.dirname(os.path.abspath(__file__)), "link_emulator.py"),
             self.robot, ROBOT_IP + "/24", self.ws, WS_IP + "/24", "--delay-ms", str(delay_ms),
             "--jitter-ms", str(jitter_ms), "--loss", str(loss), "--names", self.robot_if, self.ws_if],
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True)
        line = self.emulator.stdout.readline().strip()
        if line != "ready":
            raise RuntimeError("link_emulator.py did not start: %s%s" % (line, self.emulator.stdout.read()))
        return "user-space link (no sch_netem in this kernel): %s each way" % spec

    def close(self):
        if self.closed:
            return
        self.closed = True
        if self.emulator and self.emulator.poll() is None:
            self.emulator.kill()
            self.emulator.wait()
        for ns in (self.robot, self.ws):
            # Anything still running in the namespace goes first, then the namespace (and the veth with it).
            pids = sh("ip", "netns", "pids", ns, check=False).stdout.split()
            for pid in pids:
                try:
                    os.kill(int(pid), signal.SIGKILL)
                except (ValueError, ProcessLookupError):
                    pass
            sh("ip", "netns", "del", ns, check=False)


def host_env(ip):
    env = dict(os.environ)
    env.update(ROS_IP=ip, ROS_MASTER_URI="http://%s:%d" % (ROBOT_IP, PORT))
    env.pop("ROS_HOSTNAME", None)
    return env


class TwoHosts(unittest.TestCase):
    link = None

    @classmethod
    def setUpClass(cls):
        signal.signal(signal.SIGTERM, lambda *_: sys.exit(1))  # run the cleanup when the CI times out
        cls.link = Link()
        cls.launch_dir = os.path.realpath(os.path.join(rospkg.RosPack().get_path("scanstop_sim"), "..", "..", "launch"))
        cls.durations = {}

    @classmethod
    def tearDownClass(cls):
        if cls.link:
            cls.link.close()
        if cls.durations:
            print("two hosts: %s" % ", ".join("%s %.1f s" % kv for kv in sorted(cls.durations.items())))

    def explore(self, name):
        base = tempfile.mkdtemp(prefix="scanstop_two_hosts_%s_" % name)
        robot_dir, ws_dir = os.path.join(base, "robot"), os.path.join(base, "workstation")
        keep = bool(os.environ.get("MISSION_KEEP_RUN_DIR"))
        if not keep:
            self.addCleanup(shutil.rmtree, base, True)
        robot_env, ws_env = host_env(ROBOT_IP), host_env(WS_IP)
        for env in (robot_env, ws_env):
            env["ROS_LOG_DIR"] = os.path.join(base, "ros_log")
        robot_log = open(os.path.join(base, "robot.out"), "w")
        ws_log = open(os.path.join(base, "workstation.out"), "w")
        t0 = time.time()
        robot = subprocess.Popen(
            ["ip", "netns", "exec", self.link.robot, "roslaunch", "-p", str(PORT), "--skip-log-check",
             os.path.join(self.launch_dir, "two_host_robot.launch"), "sim:=true", "seed:=7", "planes:=50",
             "max_scans:=%d" % BUDGET, "run_dir:=%s" % robot_dir],
            env=robot_env, stdout=robot_log, stderr=subprocess.STDOUT)
        ws = None
        try:
            # The workstation joins once the robot's master and simulator answer across the link.
            deadline = time.time() + 60
            while True:
                r = subprocess.run(["ip", "netns", "exec", self.link.ws, "rosservice", "list"], env=ws_env,
                                   stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True)
                if "/scanner/take_scan" in r.stdout:
                    break
                self.assertIsNone(robot.poll(), "the robot launch ended early; see %s/robot.out" % base)
                self.assertLess(time.time(), deadline, "the workstation cannot see the robot's master and "
                                "sim_node across the link after 60 s: %s" % r.stdout[-500:])
                time.sleep(0.5)
            ws = subprocess.Popen(
                ["ip", "netns", "exec", self.link.ws, "roslaunch", "--skip-log-check",
                 os.path.join(self.launch_dir, "two_host_workstation.launch"), "run_dir:=%s" % ws_dir],
                env=ws_env, stdout=ws_log, stderr=subprocess.STDOUT)
            try:
                rc = robot.wait(timeout=TIMEOUT_S)
            except subprocess.TimeoutExpired:
                self.fail("%s: the mission did not end within %d s; see %s" % (name, TIMEOUT_S, base))
            duration = time.time() - t0
        finally:
            for p in (robot, ws):
                if p and p.poll() is None:
                    p.send_signal(signal.SIGINT)
                    try:
                        p.wait(timeout=15)
                    except subprocess.TimeoutExpired:
                        p.kill()
                        p.wait()
        self.assertEqual(rc, 0, "%s: the robot launch exited %d; see %s/robot.out" % (name, rc, base))

        # Every scan kept, exactly once: the mission's scans (robot) are the workstation's map.
        with open(os.path.join(robot_dir, "mission_state.yaml")) as f:
            state = yaml.safe_load(f)
        self.assertEqual(state["state"], "DONE", "%s: %s" % (name, state.get("last_error")))
        scans = state["scans"]
        self.assertEqual([s["index"] for s in scans], list(range(BUDGET)), name)
        with open(os.path.join(ws_dir, "map", "poses.csv")) as f:
            rows = list(csv.DictReader(f))
        self.assertEqual([int(r["index"]) for r in rows], list(range(BUDGET)), "%s: each scan stored once" % name)
        self.assertEqual(len({r["file"] for r in rows}), BUDGET)
        for s, r in zip(scans, rows):
            self.assertAlmostEqual(s["map_pose"][0], float(r["map_x"]), places=6)
            self.assertAlmostEqual(s["map_pose"][1], float(r["map_y"]), places=6)
            self.assertTrue(os.path.exists(os.path.join(ws_dir, "map", r["file"])), r["file"])
        self.assertTrue(os.path.exists(os.path.join(ws_dir, "mesh.ply")), "%s: no mesh on the workstation" % name)
        self.assertTrue(os.path.exists(os.path.join(robot_dir, "summary.json")))
        self.durations[name] = duration
        print("%s: %d scans in %.1f s" % (name, BUDGET, duration))
        return duration

    def test_1_exploration_across_two_hosts(self):
        self.explore("clean_link")

    def test_2_exploration_over_a_slow_lossy_link(self):
        how = self.link.impair(50, 10, 0.02)
        print("impaired link:", how)
        slow = self.explore("netem_link")
        clean = self.durations.get("clean_link")
        if clean is not None:
            self.assertGreater(slow, clean, "the lossy link (%.1f s) was not slower than the clean one (%.1f s)"
                               % (slow, clean))


if __name__ == "__main__":
    import rosunit
    rosunit.unitrun(PKG, "two_hosts", TwoHosts, sys.argv)
