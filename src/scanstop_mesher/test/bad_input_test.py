#!/usr/bin/env python3
"""Bad input to bpa_mesher_node (issue 9), run by bad_input.test (run directory = the parent of the
node's map_dir and the directory of its default_output, so the only place meshes may go):
- mesher/build_mesh refuses each bad request with success = false and a message saying what was
  wrong; nothing is written (the run directory's files and an earlier mesh stay byte for byte, no
  file appears outside it) and no mesh is published;
- bpa_mesher_node started with a bad parameter exits non-zero with a FATAL message naming the
  parameter, its value and the allowed range."""
import hashlib
import math
import os
import shutil
import subprocess
import time
import unittest

import roslib.packages
import rospy
import rostest
from scanstop_msgs.srv import BuildMesh, BuildMeshRequest
from visualization_msgs.msg import MarkerArray

PKG = 'scanstop_mesher'


def sphere_points(n=3000, r=1.0):
    """Evenly spread points on a sphere of radius r [m] about (0, 0, 1.5) (Fibonacci lattice)."""
    golden = math.pi * (3.0 - math.sqrt(5.0))
    pts = []
    for i in range(n):
        z = 1.0 - 2.0 * (i + 0.5) / n
        rad = math.sqrt(1.0 - z * z)
        t = golden * i
        pts.append((r * rad * math.cos(t), r * rad * math.sin(t), 1.5 + r * z))
    return pts


def write_xyz(path, pts):
    with open(path, 'w') as f:
        for p in pts:
            f.write('%.6f %.6f %.6f\n' % p)


def listing(directory):
    out = {}
    for root, _, files in os.walk(directory):
        for name in files:
            p = os.path.join(root, name)
            out[p] = hashlib.sha256(open(p, 'rb').read()).hexdigest()
    return out


def node_binary():
    found = roslib.packages.find_node(PKG, 'bpa_mesher_node')
    if not found:
        raise RuntimeError('bpa_mesher_node is not built')
    return found[0]


class MesherBadInput(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node('bpa_mesher_bad_input_test')
        cls.run_dir = rospy.get_param('~run_dir')
        os.makedirs(os.path.join(cls.run_dir, 'sub'), exist_ok=True)
        cls.outside = cls.run_dir + '_outside'
        os.makedirs(cls.outside, exist_ok=True)
        cls.markers = 0
        rospy.Subscriber('mesher/mesh_markers', MarkerArray, cls.on_markers)
        rospy.wait_for_service('mesher/build_mesh', 30.0)
        cls.build = rospy.ServiceProxy('mesher/build_mesh', BuildMesh)

    @classmethod
    def on_markers(cls, _):
        cls.markers += 1

    def test_1_bad_requests_write_nothing(self):
        run = self.run_dir
        sphere = os.path.join(run, 'sphere.xyz')
        write_xyz(sphere, sphere_points())
        good = BuildMeshRequest(input_path=sphere, output_path=os.path.join(run, 'sphere.ply'))
        r = self.build(good)
        self.assertTrue(r.success, r.message)
        self.assertGreater(r.triangles, 1000)
        self.assertEqual(r.file, os.path.join(run, 'sphere.ply'))
        end = time.time() + 10
        while self.markers < 1 and time.time() < end:
            time.sleep(0.05)
        self.assertGreaterEqual(self.markers, 1)
        time.sleep(0.5)
        markers = self.markers

        empty = os.path.join(run, 'empty.xyz')
        open(empty, 'w').close()
        nan_only = os.path.join(run, 'nan.xyz')
        open(nan_only, 'w').write('nan nan nan\n' * 10)
        garbage = os.path.join(run, 'garbage.xyz')
        open(garbage, 'w').write('1 2 three\n')
        absurd = os.path.join(run, 'absurd.xyz')  # beyond the node's max_coordinate_m (10 km)
        write_xyz(absurd, sphere_points() + [(0.0, 3.0e4, 0.0)])
        far = os.path.join(run, 'far.xyz')  # beyond what any reader accepts (100 km)
        write_xyz(far, sphere_points() + [(0.0, 3.0e7, 0.0)])
        before = listing(run)
        nan = float('nan')

        def req(**kw):
            r = BuildMeshRequest(input_path=sphere, output_path=os.path.join(run, 'sphere.ply'))
            for k, v in kw.items():
                setattr(r, k, v)
            return r

        bad = [
            ('into /etc', req(output_path='/etc/scanstop_mesh.ply'), 'lies outside the output directory'),
            ('.. out of the run directory', req(output_path=run + '/../escape.ply'), 'lies outside the output directory'),
            ('sub/../../ out of the run directory', req(output_path=run + '/sub/../../escape.ply'), 'lies outside'),
            ('relative ..', req(output_path='../escape.ply'), 'lies outside'),
            ('into a sibling directory', req(output_path=os.path.join(self.outside, 'mesh.ply')), 'lies outside'),
            ('into a missing directory', req(output_path=os.path.join(run, 'nosuch', 'mesh.ply')), 'does not exist'),
            ('.obj output', req(output_path=os.path.join(run, 'mesh.obj')), 'must end in .stl or .ply'),
            ('output onto a directory', req(output_path=os.path.join(run, 'sub')), 'must end in .stl or .ply'),
            ('NaN radius', req(radii=[0.1, nan]), "'radii_m[1]' = nan m"),
            ('decreasing radii', req(radii=[0.2, 0.1]), 'must increase'),
            ('negative radius', req(radii=[-0.1]), "'radii_m[0]' = -0.1 m"),
            ('50 m ball', req(radii=[0.1, 50.0]), "'radii_m[1]' = 50 m is out of range [0, 10 m]"),
            ('100 radii', req(radii=[0.01 * (k + 1) for k in range(100)]), '100 radii, at most 32'),
            ('NaN voxel', req(voxel_m=nan), "'voxel_m' = nan m is out of range"),
            ('negative voxel', req(voxel_m=-0.5), "'voxel_m' = -0.5 m is out of range [0, 10 m]"),
            ('1 km voxel', req(voxel_m=1000.0), "'voxel_m' = 1000 m is out of range [0, 10 m]"),
            ('missing input', req(input_path=os.path.join(run, 'missing.ply')), 'missing.ply'),
            ('empty input', req(input_path=empty), 'empty.xyz: no points'),
            ('all-NaN input', req(input_path=nan_only), 'no finite points'),
            ('corrupt input', req(input_path=garbage), 'garbage.xyz'),
            ('absurd coordinates', req(input_path=absurd), 'absurd coordinates'),
            ('a point at 3e7 m', req(input_path=far), 'far.xyz: point 3000 (0, 3e+07, 0) lies beyond the 100000 m coordinate limit'),
            ('no map yet (empty input_path)', req(input_path=''), 'poses.csv'),
        ]
        for what, request, text in bad:
            r = self.build(request)
            self.assertFalse(r.success, 'accepted: ' + what)
            self.assertIn(text, r.message, what)
        time.sleep(0.5)
        self.assertEqual(listing(run), before, 'a refused request changed the run directory')
        self.assertFalse(os.path.exists('/etc/scanstop_mesh.ply'))
        self.assertFalse(os.path.exists(os.path.join(os.path.dirname(run), 'escape.ply')))
        self.assertEqual(os.listdir(self.outside), [])
        self.assertFalse(os.path.exists(os.path.join(run, 'map')), 'a refused request created the map directory')
        self.assertEqual(self.markers, markers, 'a refused request published a mesh')

        # A relative path inside the run directory is fine.
        r = self.build(req(output_path='sub/sphere.stl'))
        self.assertTrue(r.success, r.message)
        self.assertEqual(r.file, os.path.join(run, 'sub', 'sphere.stl'))

    def check_bad_param(self, index, params, *expected):
        args = [node_binary(), '__name:=bad_mesher_%d' % index] + ['_%s:=%s' % kv for kv in params]
        proc = subprocess.run(args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=30,
                              universal_newlines=True)
        self.assertNotEqual(proc.returncode, 0, 'bpa_mesher_node with %s exited 0:\n%s' % (params, proc.stdout))
        self.assertIn('FATAL', proc.stdout, proc.stdout)
        for text in expected:
            self.assertIn(text, proc.stdout, 'expected %r for %s:\n%s' % (text, params, proc.stdout))

    def test_2_bad_parameters_stop_the_node(self):
        self.check_bad_param(1, [('map_voxel_m', '-0.1')], "'map_voxel_m' = -0.1 m is out of range [0, 10 m]")
        self.check_bad_param(2, [('max_coordinate_m', '0.5')], "'max_coordinate_m' = 0.5 m is out of range [1, 1e+06 m]")
        self.check_bad_param(3, [('normal_min_neighbors', '1')], "'normal_min_neighbors' = 1 is out of range [3, 1000]")
        self.check_bad_param(4, [('color_mode', 'rainbow')], "'color_mode'", 'rainbow')
        self.check_bad_param(5, [('default_output', '/tmp/mesh.obj')], "'default_output' = '/tmp/mesh.obj' must end in .stl or .ply")
        self.check_bad_param(6, [('map_poll_s', '0')], "'map_poll_s' = 0 s must be a finite value > 0")
        self.check_bad_param(7, [('map_voxel_m', 'fine')], "parameter '/bad_mesher_7/map_voxel_m' has the wrong type")
        self.check_bad_param(8, [('map_voxel', '0.01')], "unknown parameter '/bad_mesher_8/map_voxel' (did you mean "
                             "'map_voxel_m'?): nothing reads it; bpa_mesher_node reads ", "fused_carve_m")

    @classmethod
    def tearDownClass(cls):
        for d in (cls.run_dir, cls.outside):
            if d.startswith('/tmp/'):
                shutil.rmtree(d, ignore_errors=True)


if __name__ == '__main__':
    rostest.rosrun(PKG, 'bpa_mesher_bad_input', MesherBadInput)
