#!/usr/bin/env python3
"""Open3D's Ball Pivoting on a PLY point cloud with normals: best time of N runs, triangles and
non-manifold edges/vertices. Usage: open3d_bpa.py POINTS.ply r1[,r2,...] [repeat] [OUT.ply]"""
import sys
import time

import open3d as o3d


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    path, radii = sys.argv[1], [float(r) for r in sys.argv[2].split(",")]
    repeat = int(sys.argv[3]) if len(sys.argv) > 3 else 3
    pcd = o3d.io.read_point_cloud(path)
    if not pcd.has_normals():
        sys.exit("open3d_bpa.py: %s has no normals" % path)
    best, mesh = 1e9, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        mesh = o3d.geometry.TriangleMesh.create_from_point_cloud_ball_pivoting(pcd, o3d.utility.DoubleVector(radii))
        best = min(best, time.perf_counter() - t0)
    if len(sys.argv) > 4:
        o3d.io.write_triangle_mesh(sys.argv[4], mesh)
    print("%-34s %9.3f s %9d triangles %6d nm-edges %6d nm-vertices" % (
        "Open3D %s radii %s" % (o3d.__version__, " ".join(str(r) for r in radii)), best, len(mesh.triangles),
        len(mesh.get_non_manifold_edges()), len(mesh.get_non_manifold_vertices())))


if __name__ == "__main__":
    main()
