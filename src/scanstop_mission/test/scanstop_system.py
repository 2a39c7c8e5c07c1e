"""The simulated system as the system-level tests drive it: starts, kills (SIGKILL) and restarts
sim_node, icp_slam_node, explorer_node, bpa_mesher_node and mission_node on one run directory, as
roslaunch with respawn="true" would, and checks what a finished run left behind.

Used by mission_sim_rostest.py (crashes) and mission_chaos_rostest.py (seeded kills of every node).
"""
import csv
import json
import os
import shutil
import signal
import subprocess
import tempfile
import time
import unittest

import yaml

NODE_NAMES = {
    "sim": "sim_node",
    "slam": "icp_slam_node",
    "explorer": "explorer_node",
    "mesher": "bpa_mesher_node",
    "mission": "mission_node",
}


def world_file(world):
    """The STL of a world in the repository's worlds/ (room_10x8, office_loop, corridor)."""
    import rospkg
    return os.path.realpath(os.path.join(rospkg.RosPack().get_path("scanstop_sim"), "..", "..", "worlds",
                                         world + ".stl"))


def mission_scans(run_dir):
    """The scans mission_state.yaml records (empty while there is none or while it is unreadable)."""
    try:
        with open(os.path.join(run_dir, "mission_state.yaml")) as f:
            state = yaml.safe_load(f) or {}
        return state.get("scans") or []
    except (OSError, yaml.YAMLError):
        return []


def map_rows(run_dir):
    """The rows of the SLAM map's poses.csv."""
    with open(os.path.join(run_dir, "map", "poses.csv")) as f:
        return list(csv.DictReader(f))


def summary(run_dir):
    with open(os.path.join(run_dir, "summary.json")) as f:
        return json.load(f)


class System(object):
    """The nodes of one simulated exploration, logging into <run_dir>/<name>.out."""

    def __init__(self, run_dir, planes=50, budget=6, world="room_10x8", seed=7, error_profile="thesis",
                 mission_args=(), sim_args=(), slam_args=()):
        self.run_dir = run_dir
        self.planes = planes
        self.budget = budget
        self.world = world
        self.seed = seed
        self.error_profile = error_profile
        self.mission_args = list(mission_args)
        self.sim_args = list(sim_args)
        self.slam_args = list(slam_args)
        self.procs = {}
        self.starts = {}

    def args(self, name):
        run = self.run_dir
        return {
            "sim": ["rosrun", "scanstop_sim", "sim_node", "__name:=sim_node", "_world:=%s" % world_file(self.world),
                    "_error_profile:=%s" % self.error_profile, "_seed:=%d" % self.seed,
                    "_state_file:=%s/sim_state.txt" % run] + self.sim_args,
            "slam": ["rosrun", "scanstop_slam", "icp_slam_node", "__name:=icp_slam_node", "_map_dir:=%s/map" % run] + self.slam_args,
            "explorer": ["rosrun", "scanstop_explorer", "explorer_node", "__name:=explorer_node",
                         "_map_dir:=%s/map" % run, "_run_dir:=%s/explorer" % run, "_k_r_m:=2.5"],
            "mesher": ["rosrun", "scanstop_mesher", "bpa_mesher_node", "__name:=bpa_mesher_node",
                       "_map_dir:=%s/map" % run, "_default_output:=%s/mesh.ply" % run],
            "mission": ["rosrun", "scanstop_mission", "mission_node", "__name:=mission_node", "_run_dir:=%s" % run,
                        "_map_dir:=%s/map" % run, "_planes:=%d" % self.planes, "_max_scans:=%d" % self.budget,
                        "_world:=%s" % self.world, "_shutdown_when_done:=true",
                        "_wait_for_service_timeout_s:=60.0"] + self.mission_args,
        }[name]

    def start(self, name):
        log = open(os.path.join(self.run_dir, "%s.out" % name), "a")
        log.write("=== start %s at %.3f\n" % (name, time.time()))
        log.flush()
        self.procs[name] = subprocess.Popen(self.args(name), stdout=log, stderr=subprocess.STDOUT,
                                            start_new_session=True)
        self.starts[name] = self.starts.get(name, 0) + 1

    def kill(self, name):
        """SIGKILL to the node itself (rosrun execs it: the Popen pid is the node's)."""
        p = self.procs[name]
        try:
            os.killpg(p.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        p.wait()

    def respawn(self, name, delay=0.2):
        """Kill and restart, as roslaunch's respawn would after noticing the death."""
        self.kill(name)
        time.sleep(delay)
        self.start(name)

    def alive(self, name):
        return name in self.procs and self.procs[name].poll() is None

    def wait_mission(self, timeout):
        """Waits for mission_node to end; returns its exit code or None on timeout."""
        try:
            return self.procs["mission"].wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            return None

    def wait_for_scans(self, n, timeout):
        deadline = time.time() + timeout
        while time.time() < deadline:
            if len(mission_scans(self.run_dir)) >= n:
                return True
            if not self.alive("mission"):
                return False
            time.sleep(0.2)
        return False

    def stop_all(self):
        for name in list(self.procs):
            if self.alive(name):
                self.kill(name)


class SystemTestCase(unittest.TestCase):
    """A test case on one simulated system: setUp makes a fresh run directory (RUN_DIR_PREFIX) and
    the System of system_args() (SYSTEM_ARGS: System's keyword arguments); tearDown stops every node
    and removes the run directory (kept, and named, with MISSION_KEEP_RUN_DIR set)."""
    RUN_DIR_PREFIX = "scanstop_rostest_"
    SYSTEM_ARGS = {}

    def system_args(self):
        return dict(self.SYSTEM_ARGS)

    def setUp(self):
        self.run_dir = tempfile.mkdtemp(prefix=self.RUN_DIR_PREFIX)
        self.system = System(self.run_dir, **self.system_args())

    def tearDown(self):
        self.system.stop_all()
        if os.environ.get("MISSION_KEEP_RUN_DIR"):
            print("run directory kept:", self.run_dir)
        else:
            shutil.rmtree(self.run_dir, ignore_errors=True)


def check_every_scan_once(test, run_dir, budget):
    """The run ended DONE with `budget` scans, each in the mission state and in the SLAM map exactly
    once, in order, with the same pose, each scan file present. Returns (summary, scans)."""
    s = summary(run_dir)
    test.assertEqual(s["state"], "DONE", s)
    test.assertEqual(s["scans"], budget, s)
    scans = mission_scans(run_dir)
    test.assertEqual([x["index"] for x in scans], list(range(budget)), "mission scans in %s" % run_dir)
    rows = map_rows(run_dir)
    test.assertEqual([int(r["index"]) for r in rows], list(range(budget)), "each scan stored once in %s" % run_dir)
    files = [r["file"] for r in rows]
    test.assertEqual(len(set(files)), len(files), "distinct scan files")
    for x, r in zip(scans, rows):
        test.assertAlmostEqual(x["map_pose"][0], float(r["map_x"]), places=6)
        test.assertAlmostEqual(x["map_pose"][1], float(r["map_y"]), places=6)
        test.assertTrue(os.path.exists(os.path.join(run_dir, "map", r["file"])), r["file"])
    return s, scans
