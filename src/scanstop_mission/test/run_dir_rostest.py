#!/usr/bin/env python3
"""mission_node and the run directory (issue 22, "fail fast, say why, lose nothing").

A finished room_10x8 run directory reused for world:=corridor, a run_dir that is a regular file and
a missing world file each end mission_node within 15 s, non-zero, with a FATAL line naming the cause
and what to do; the room's run is left as it was. The same run is accepted (the node stays up)."""
import os
import shutil
import subprocess
import sys
import tempfile
import time
import unittest

import rospkg

PKG = "scanstop_mission"
WORLDS = os.path.normpath(os.path.join(rospkg.RosPack().get_path(PKG), "..", "..", "worlds"))
ROOM = os.path.join(WORLDS, "room_10x8.stl")
CORRIDOR = os.path.join(WORLDS, "corridor.stl")
# As sim_explore.launch sets it (a map: roscpp's _name:=value mappings take scalars only).
IDENTITY = '{start_pose: "", error_profile: thesis, seed: "1"}'


class RunDir(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="scanstop_run_dir_")
        self.proc = None

    def tearDown(self):
        if self.proc and self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()
        shutil.rmtree(self.tmp, ignore_errors=True)

    def start(self, params):
        subprocess.call(["rosparam", "delete", "/mission_node"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        subprocess.check_call(["rosparam", "set", "/mission_node/run_identity", IDENTITY])
        args = ["rosrun", PKG, "mission_node", "__name:=mission_node", "_autostart:=false", "_planes:=50",
                "_wait_for_service_timeout_s:=5.0"] + params
        self.proc = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True)

    def fails_fast(self, params, *fragments):
        t0 = time.time()
        self.start(params)
        try:
            out, _ = self.proc.communicate(timeout=15)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            out, _ = self.proc.communicate()
            self.fail("%s: mission_node did not fail within 15 s:\n%s" % (params, out))
        self.assertNotEqual(self.proc.returncode, 0, out)
        fatal = [l for l in out.splitlines() if "FATAL" in l]
        self.assertTrue(fatal, out)
        for f in fragments:
            self.assertIn(f, fatal[-1], "the FATAL line lacks %r:\n%s" % (f, out))
        print("%.1f s -> %s" % (time.time() - t0, fatal[-1]))

    def room_run(self):
        """A finished room_10x8 run: its identity as mission_node records it, and its mission (one scan: a
        mission that took none is set aside by a later launch, not defended)."""
        run = os.path.join(self.tmp, "room")
        self.start(["_run_dir:=" + run, "_world:=room_10x8", "_world_file:=" + ROOM])
        deadline = time.time() + 15
        while not os.path.exists(os.path.join(run, "run_identity.yaml")) and time.time() < deadline:
            time.sleep(0.2)
        self.proc.kill()
        self.proc.wait()
        self.assertTrue(os.path.exists(os.path.join(run, "run_identity.yaml")), "no run_identity.yaml in %s" % run)
        with open(os.path.join(run, "mission_state.yaml"), "w") as f:
            f.write("state: DONE\nworld: room_10x8\nlast_map_pose: [0, 0, 0]\nodom_at_last_scan: [0, 0, 0]\n"
                    "odom_now: [0, 0, 0]\nscans:\n  - index: 0\n    map_pose: [0, 0, 0]\n    odom_pose: [0, 0, 0]\n")
        return run

    def test_a_room_run_dir_is_refused_for_the_corridor(self):
        run = self.room_run()
        before = {n: open(os.path.join(run, n)).read() for n in ("run_identity.yaml", "mission_state.yaml")}
        self.fails_fast(["_run_dir:=" + run, "_world:=corridor", "_world_file:=" + CORRIDOR],
                        run, "holds another run's mission", "world is 'room_10x8' there, 'corridor' now",
                        "world_file_fnv1a64", "use a new run_dir", "delete this one")
        after = {n: open(os.path.join(run, n)).read() for n in before}
        self.assertEqual(before, after, "the room's run was changed")

    def test_the_same_run_is_resumed(self):
        run = self.room_run()
        self.start(["_run_dir:=" + run, "_world:=room_10x8", "_world_file:=" + ROOM])
        time.sleep(4.0)
        if self.proc.poll() is not None:
            self.fail("mission_node refused its own run:\n%s" % self.proc.communicate()[0])

    def test_a_regular_file_as_run_dir(self):
        path = os.path.join(self.tmp, "a_file")
        open(path, "w").write("not a directory\n")
        self.fails_fast(["_run_dir:=" + path], path, "exists but is a regular file, not a directory")
        self.fails_fast(["_run_dir:=" + path + "/run"], path + "/run", "cannot create the run directory (Not a directory)")

    def test_a_missing_world_file(self):
        missing = os.path.join(self.tmp, "corridr.stl")
        self.fails_fast(["_run_dir:=" + os.path.join(self.tmp, "run"), "_world:=corridr", "_world_file:=" + missing],
                        "world_file' = '%s'" % missing, "no such file")


if __name__ == "__main__":
    import rostest
    rostest.rosrun(PKG, "mission_run_dir", RunDir, sys.argv)
