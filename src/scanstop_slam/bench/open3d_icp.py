#!/usr/bin/env python3
"""Open3D's point-to-point (or point-to-plane) ICP on one pair, for slam_bench.sh: prints one JSON
object like icp_register --json (translation, quaternion, yaw, iterations, rms, fitness, time_s,
open3d version).

usage: open3d_icp.py TARGET SOURCE --init x,y,z,yaw_deg --c-max M [--max-iterations N] [--relative R] [--voxel M]
                     [--method point_to_point|point_to_plane] [--normal-radius M] [--normal-nn N]
Open3D's own convergence test (relative fitness and RMSE change below --relative) ends the iteration;
Open3D does not report the iteration count. point_to_plane: the target's normals are estimated
first (hybrid search: at most --normal-nn neighbours within --normal-radius); time_s includes
that, normals_s is it alone.
"""
import argparse
import json
import math
import sys
import time

import numpy as np


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("target")
    ap.add_argument("source")
    ap.add_argument("--init", required=True, help="x,y,z,yaw_deg of SOURCE in TARGET's frame")
    ap.add_argument("--c-max", type=float, required=True, help="max correspondence distance [m]")
    ap.add_argument("--max-iterations", type=int, default=100)
    ap.add_argument("--relative", type=float, default=1e-6,
                    help="Open3D's relative fitness and RMSE change that ends the iteration (default 1e-6)")
    ap.add_argument("--voxel", type=float, default=0.0, help="voxel-downsample the source first [m] (0 = no)")
    ap.add_argument("--method", choices=["point_to_point", "point_to_plane"], default="point_to_point")
    ap.add_argument("--normal-radius", type=float, default=0.1, help="target normal estimation radius [m]")
    ap.add_argument("--normal-nn", type=int, default=30, help="target normal estimation neighbours")
    a = ap.parse_args()
    import open3d as o3d
    try:
        x, y, z, yaw_deg = (float(v) for v in a.init.split(","))
    except ValueError:
        sys.exit("open3d_icp.py: --init must be x,y,z,yaw_deg, not '%s'" % a.init)
    target = o3d.io.read_point_cloud(a.target)
    source = o3d.io.read_point_cloud(a.source)
    for path, cloud in ((a.target, target), (a.source, source)):
        if len(cloud.points) == 0:
            sys.exit("open3d_icp.py: %s has no points (or could not be read)" % path)
    if a.voxel > 0:
        source = source.voxel_down_sample(a.voxel)
    yaw = math.radians(yaw_deg)
    init = np.eye(4)
    init[:2, :2] = [[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]]
    init[:3, 3] = [x, y, z]
    start = time.perf_counter()
    estimation = o3d.pipelines.registration.TransformationEstimationPointToPoint()
    if a.method == "point_to_plane":
        target.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(radius=a.normal_radius, max_nn=a.normal_nn))
        estimation = o3d.pipelines.registration.TransformationEstimationPointToPlane()
    normals_s = time.perf_counter() - start
    r = o3d.pipelines.registration.registration_icp(
        source, target, a.c_max, init, estimation,
        o3d.pipelines.registration.ICPConvergenceCriteria(
            relative_fitness=a.relative, relative_rmse=a.relative, max_iteration=a.max_iterations))
    elapsed = time.perf_counter() - start
    T = np.asarray(r.transformation)
    R = T[:3, :3]
    # Quaternion (x, y, z, w) from the rotation matrix.
    w = math.sqrt(max(0.0, 1.0 + R[0, 0] + R[1, 1] + R[2, 2])) / 2.0
    qx = math.copysign(math.sqrt(max(0.0, 1.0 + R[0, 0] - R[1, 1] - R[2, 2])) / 2.0, R[2, 1] - R[1, 2])
    qy = math.copysign(math.sqrt(max(0.0, 1.0 - R[0, 0] + R[1, 1] - R[2, 2])) / 2.0, R[0, 2] - R[2, 0])
    qz = math.copysign(math.sqrt(max(0.0, 1.0 - R[0, 0] - R[1, 1] + R[2, 2])) / 2.0, R[1, 0] - R[0, 1])
    print(json.dumps({
        "translation": [float(v) for v in T[:3, 3]],
        "quaternion": [qx, qy, qz, w],
        "yaw": math.atan2(R[1, 0], R[0, 0]),
        "rms": r.inlier_rmse, "fitness": r.fitness, "correspondences": len(r.correspondence_set),
        "time_s": elapsed, "normals_s": normals_s, "method": a.method, "source_points": len(source.points), "open3d": o3d.__version__}))


if __name__ == "__main__":
    main()
