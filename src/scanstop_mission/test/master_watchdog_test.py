#!/usr/bin/env python3
"""The ROS master going away mid-run (issue #22 class 5): a private rosmaster on a free loopback
port; sim_node, icp_slam_node, explorer_node, bpa_mesher_node and mission_node (autostart off) each
with master_timeout_s = 8 s.

1. The master hangs for 5 s (SIGSTOP, then SIGCONT: the same master): every node logs one ERROR
   naming the master URI and how long it has been gone, then "is back after"; sim_node refuses a
   base/forward meanwhile (persistent connection, no master needed) and accepts it once the master
   is back; mission_node pauses and resumes; every node keeps running.
2. The master is killed (SIGKILL): the same ERROR, then after master_timeout_s every node ends with
   exit code 1 naming "has been unreachable for ... (master_timeout_s = 8.0 s)"; the mission ends
   FAILED with that reason in mission_state.yaml.

Not a rostest: it owns its master (rostest's would be killed). Run by run_tests_scanstop_mission
(catkin_run_tests_target master_watchdog); about 40 s."""
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import unittest

import rospkg

PKG = "scanstop_mission"
ROOT = os.path.normpath(os.path.join(rospkg.RosPack().get_path(PKG), "..", ".."))
ROOM = os.path.join(ROOT, "worlds", "room_10x8.stl")
TIMEOUT_S = 8.0
NODES = ["sim_node", "icp_slam_node", "explorer_node", "bpa_mesher_node", "mission_node"]


def free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def wait_for(predicate, timeout_s, step_s=0.1):
    deadline = time.time() + timeout_s
    while time.time() < deadline:
        if predicate():
            return True
        time.sleep(step_s)
    return predicate()


class MasterWatchdog(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.procs, cls.master = {}, None
        try:
            cls.start()
        except BaseException:
            cls.tearDownClass()  # not called by unittest when setUpClass fails
            raise

    @classmethod
    def start(cls):
        cls.tmp = tempfile.mkdtemp(prefix="scanstop_master_wd_")
        cls.port = free_port()
        cls.uri = "http://127.0.0.1:%d" % cls.port
        cls.env = dict(os.environ, ROS_MASTER_URI=cls.uri, ROS_IP="127.0.0.1", ROS_LOG_DIR=os.path.join(cls.tmp, "log"))
        cls.env.pop("ROS_HOSTNAME", None)
        cls.master = subprocess.Popen(["rosmaster", "--core", "-p", str(cls.port)], env=cls.env,
                                      stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        ok = wait_for(lambda: subprocess.call(["rosparam", "set", "/up", "1"], env=cls.env, stdout=subprocess.DEVNULL,
                                              stderr=subprocess.DEVNULL) == 0, 20, 0.3)
        assert ok, "the private rosmaster on %s did not come up" % cls.uri
        subprocess.check_call(["rosparam", "load", os.path.join(ROOT, "config", "sim.yaml"), "/sim_node"], env=cls.env)
        subprocess.check_call(["rosparam", "set", "/mission_node/run_identity",
                               '{start_pose: "", error_profile: perfect, seed: "1"}'], env=cls.env)
        run = os.path.join(cls.tmp, "run")
        os.makedirs(run)
        cls.run_dir = run
        common = ["_master_timeout_s:=%.1f" % TIMEOUT_S]
        args = {
            "sim_node": ("scanstop_sim", ["_world:=" + ROOM, "_error_profile:=perfect", "_odom_as_map:=true"]),
            "icp_slam_node": ("scanstop_slam", ["_map_dir:=" + os.path.join(run, "map")]),
            "explorer_node": ("scanstop_explorer", ["_map_dir:=" + os.path.join(run, "map"),
                                                    "_run_dir:=" + os.path.join(run, "explorer")]),
            "bpa_mesher_node": ("scanstop_mesher", ["_map_dir:=" + os.path.join(run, "map")]),
            "mission_node": (PKG, ["_run_dir:=" + run, "_world:=room_10x8", "_autostart:=false", "_planes:=50",
                                   "_wait_for_service_timeout_s:=5.0"]),
        }
        cls.logs = {}
        for name in NODES:
            pkg, extra = args[name]
            log = os.path.join(cls.tmp, name + ".out")
            cls.logs[name] = log
            with open(log, "w") as out:
                cls.procs[name] = subprocess.Popen(["rosrun", pkg, name, "__name:=" + name] + common + extra,
                                                   env=cls.env, stdout=out, stderr=subprocess.STDOUT)
        up = wait_for(lambda: all("/" + n in cls.nodes_known() for n in NODES), 40, 0.5)
        assert up, "not every node registered: %s\n%s" % (cls.nodes_known(), cls.dump())

    @classmethod
    def tearDownClass(cls):
        for p in cls.procs.values():
            if p.poll() is None:
                p.kill()
                p.wait()
        if cls.master and cls.master.poll() is None:
            cls.master.send_signal(signal.SIGCONT)
            cls.master.kill()
            cls.master.wait()
        shutil.rmtree(cls.tmp, ignore_errors=True)

    @classmethod
    def nodes_known(cls):
        r = subprocess.run(["rosnode", "list"], env=cls.env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                           universal_newlines=True, timeout=10)
        return r.stdout.split()

    @classmethod
    def dump(cls):
        return "\n".join("--- %s:\n%s" % (n, cls.text(n)[-3000:]) for n in NODES)

    @classmethod
    def text(cls, name):
        with open(cls.logs[name]) as f:
            return f.read()

    def lines(self, name, fragment):
        return [l for l in self.text(name).splitlines() if fragment in l]

    def forward(self, proxy):
        return proxy(distance_m=0.05)

    def test_1_a_hung_master_that_comes_back(self):
        import rospy
        from scanstop_msgs.srv import Forward
        os.environ.update(ROS_MASTER_URI=self.uri, ROS_IP="127.0.0.1")
        rospy.wait_for_service("/base/forward", timeout=20)
        proxy = rospy.ServiceProxy("/base/forward", Forward, persistent=True)
        self.assertTrue(self.forward(proxy).success)  # connected before the outage
        self.master.send_signal(signal.SIGSTOP)
        stopped_at = time.time()
        lost = "the ROS master at %s is unreachable (gone for" % self.uri
        try:
            self.assertTrue(wait_for(lambda: all(self.lines(n, lost) for n in NODES), 15), self.dump())
            r = self.forward(proxy)
            self.assertFalse(r.success, r.message)
            self.assertIn("refused: the ROS master at %s is unreachable" % self.uri, r.message)
            self.assertTrue(wait_for(lambda: self.lines("mission_node", "mission: paused until the ROS master is back"), 5),
                            self.text("mission_node"))
            time.sleep(max(0.0, stopped_at + 5.0 - time.time()))  # a 5 s outage
        finally:
            self.master.send_signal(signal.SIGCONT)
        back = "the ROS master at %s is back after" % self.uri
        self.assertTrue(wait_for(lambda: all(self.lines(n, back) for n in NODES), 15), self.dump())
        for n in NODES:
            said = self.lines(n, "%s: %s" % (n, lost))  # the watchdog's line (the mission also records it)
            self.assertEqual(len(said), 1, "%s: the ERROR is said once\n%s" % (n, self.text(n)))
            self.assertIn("ERROR", said[0])
            self.assertIsNone(self.procs[n].poll(), "%s ended\n%s" % (n, self.text(n)))
        self.assertTrue(wait_for(lambda: self.lines("mission_node", "mission: resumed: the ROS master is back"), 5))
        self.assertTrue(self.forward(proxy).success)
        proxy.close()

    def test_2_a_killed_master_ends_every_node_naming_why(self):
        before = {n: len(self.lines(n, "is unreachable (gone for")) for n in NODES}
        t0 = time.time()
        self.master.kill()
        self.master.wait()
        self.assertTrue(wait_for(lambda: all(len(self.lines(n, "is unreachable (gone for")) > before[n] for n in NODES), 10),
                        self.dump())
        ended = lambda: all(p.poll() is not None for p in self.procs.values())
        self.assertTrue(wait_for(ended, TIMEOUT_S + 20), self.dump())
        took = time.time() - t0
        self.assertGreaterEqual(took, TIMEOUT_S - 1.0)
        why = "the ROS master at %s has been unreachable for" % self.uri
        for n in NODES:
            self.assertEqual(self.procs[n].returncode, 1, "%s exit code\n%s" % (n, self.text(n)))
            self.assertTrue(self.lines(n, why), "%s\n%s" % (n, self.text(n)))
            self.assertIn("(master_timeout_s = 8.0 s); the node ends", self.lines(n, why)[0])
        with open(os.path.join(self.run_dir, "mission_state.yaml")) as f:
            state = f.read()
        self.assertIn("FAILED", state)
        self.assertIn(why, state)
        print("every node ended %.1f s after the master was killed" % took)


if __name__ == "__main__":
    import rosunit
    rosunit.unitrun(PKG, "master_watchdog", MasterWatchdog, sys.argv)
