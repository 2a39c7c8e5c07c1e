#!/usr/bin/env python3
"""Open3D's quadric decimation (the peer of decimate_mesh) on a mesh file, to a triangle count.

usage: open3d_decimate.py INPUT OUTPUT TARGET_TRIANGLES
Prints one JSON object: triangles before and after, the decimation's wall time (the reading and
writing not counted), and the boundary edges after.
"""
import json
import sys
import time

import open3d as o3d


def main():
    if len(sys.argv) != 4:
        sys.stderr.write(__doc__)
        return 2
    src, dst, target = sys.argv[1], sys.argv[2], int(sys.argv[3])
    mesh = o3d.io.read_triangle_mesh(src)
    if len(mesh.triangles) == 0:
        sys.stderr.write("open3d_decimate: %s has no triangles\n" % src)
        return 1
    before = len(mesh.triangles)
    t0 = time.perf_counter()
    out = mesh.simplify_quadric_decimation(target)
    seconds = time.perf_counter() - t0
    o3d.io.write_triangle_mesh(dst, out)
    print(json.dumps({"peer": "open3d %s simplify_quadric_decimation" % o3d.__version__, "faces_before": before,
                      "faces_after": len(out.triangles), "seconds": round(seconds, 3),
                      "edge_manifold": bool(out.is_edge_manifold(allow_boundary_edges=True)),
                      "vertex_manifold": bool(out.is_vertex_manifold())}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
