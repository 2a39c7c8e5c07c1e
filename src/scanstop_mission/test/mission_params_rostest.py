#!/usr/bin/env python3
"""mission_node validates its parameters at start and its control requests.

Bad parameters: for each case mission_node must exit non-zero within 30 s, printing a message that
names the parameter, the bad value and what is allowed. Control requests (mission/start, pause,
resume, abort): each one that does not apply is answered success = false with the reason.
"""
import os
import shutil
import subprocess
import sys
import tempfile
import time
import unittest

import rospy
from std_srvs.srv import Trigger

PKG = "scanstop_mission"

# (parameters, fragments the error message must contain)
BAD_PARAMETERS = [
    (["_planes:=37"], ["'planes'", "37", "must be one of 50, 100, 200, 400"]),
    (["_planes:=abc"], ["/mission_node/planes", "wrong type"]),
    (["_max_scans:=-3"], ["'max_scans'", "-3", "out of range [0, 100000]"]),
    # d_max has one source, the explorer's d_max_m (every plan says it): the mission has none.
    (["_d_max:=2.0"], ["unknown parameter '/mission_node/d_max'"]),
    (["_min_scan_travel_m:=-1.0"], ["'min_scan_travel_m'", "-1 m", "out of range [0, 100 m]"]),
    (["_heading_tolerance_rad:=3.0"], ["'heading_tolerance_rad'", "3 rad", "out of range [0, 0.5 rad]"]),
    (["_max_step_retries:=1000"], ["'max_step_retries'", "1000", "out of range [0, 100]"]),
    (["_max_consecutive_failed_cycles:=0"], ["'max_consecutive_failed_cycles'", "0", "out of range [1, 1000]"]),
    (["_scan_timeout_s:=-5.0"], ["/mission_node/scan_timeout_s", "-5", "must be in (0, 1e6) s"]),
    (["_wait_for_service_timeout_s:=0.0"], ["/mission_node/wait_for_service_timeout_s", "must be in (0, 1e6) s"]),
    (["_mesh_output:=/tmp/mesh.obj"], ["'mesh_output'", "/tmp/mesh.obj", "must end in .ply or .stl"]),
    (["_map_dir:="], ["/mission_node/map_dir", "empty"]),
    (["_plannes:=50"], ["unknown parameter '/mission_node/plannes' (did you mean 'planes'?): nothing reads it; "
                        "mission_node reads ", "max_scans"]),
    (["_run_dir:=/proc/scanstop_no_such_dir"], ["/proc/scanstop_no_such_dir", "cannot create the run directory"]),
    ([None], ["required parameter '/mission_node/run_dir' is not set"]),
]


class MissionParams(unittest.TestCase):
    def setUp(self):
        self.run_dir = tempfile.mkdtemp(prefix="scanstop_mission_params_")
        self.proc = None

    def tearDown(self):
        if self.proc and self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()
        shutil.rmtree(self.run_dir, ignore_errors=True)

    def node(self, params, with_run_dir=True):
        args = ["rosrun", PKG, "mission_node", "__name:=mission_node"]
        if with_run_dir and not any(p.startswith("_run_dir:=") for p in params):
            args.append("_run_dir:=%s/run" % self.run_dir)
        # Parameters left on the server by a previous case would leak into the next one.
        subprocess.call(["rosparam", "delete", "/mission_node"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        return subprocess.Popen(args + params, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                universal_newlines=True)

    def test_bad_parameters_stop_the_node_with_a_clear_message(self):
        for params, fragments in BAD_PARAMETERS:
            with_run_dir = params != [None]
            self.proc = self.node([p for p in params if p is not None], with_run_dir)
            try:
                out, _ = self.proc.communicate(timeout=30)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                out, _ = self.proc.communicate()
                self.fail("%s: mission_node did not exit within 30 s:\n%s" % (params, out))
            self.assertNotEqual(self.proc.returncode, 0, "%s: exit code 0\n%s" % (params, out))
            for f in fragments:
                self.assertIn(f, out, "%s: the message lacks %r:\n%s" % (params, f, out))
            print("%s -> %s" % (" ".join(p for p in params if p) or "(no run_dir)",
                                [l for l in out.splitlines() if "FATAL" in l][-1:]))

    def call(self, name):
        rospy.wait_for_service("mission/" + name, timeout=30)
        return rospy.ServiceProxy("mission/" + name, Trigger)()

    def test_control_requests_that_do_not_apply_are_refused(self):
        rospy.init_node("mission_params_test", anonymous=True, disable_signals=True)
        # No scanner runs: a started mission waits for scanner/take_scan meanwhile.
        self.proc = self.node(["_autostart:=false", "_wait_for_service_timeout_s:=8.0", "_planes:=50"])
        r = self.call("pause")
        self.assertFalse(r.success)
        self.assertIn("no mission is running", r.message)
        for name in ("resume", "abort"):
            r = self.call(name)
            self.assertFalse(r.success, name)
            self.assertIn("no mission is running", r.message)
        r = self.call("start")
        self.assertTrue(r.success, r.message)
        r = self.call("start")
        self.assertFalse(r.success)
        self.assertIn("already running", r.message)
        r = self.call("resume")
        self.assertFalse(r.success)
        self.assertIn("not paused", r.message)
        self.assertTrue(self.call("pause").success)
        r = self.call("pause")
        self.assertFalse(r.success)
        self.assertIn("already paused", r.message)
        self.assertTrue(self.call("resume").success)
        self.assertTrue(self.call("abort").success)
        r = self.call("abort")
        self.assertFalse(r.success)
        self.assertIn("refused", r.message)
        # The aborted mission ends ABORTED (after its wait for the scanner) and the node stays up.
        deadline = time.time() + 40
        while time.time() < deadline:
            path = os.path.join(self.run_dir, "run", "mission_state.yaml")
            if os.path.exists(path) and "state: ABORTED" in open(path).read():
                break
            time.sleep(0.5)
        else:
            self.fail("the aborted mission did not end ABORTED")
        self.assertIsNone(self.proc.poll())


if __name__ == "__main__":
    import rostest
    rostest.rosrun(PKG, "mission_params", MissionParams, sys.argv)
