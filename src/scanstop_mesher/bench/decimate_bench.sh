#!/bin/bash
# Decimation benchmark: decimate_mesh (ours, the node's default bound) next to Open3D's quadric
# decimation (python3-open3d) to the same triangle count, on the same mesh in the same run; with a
# world, both meshes' distances to its true surfaces and the visible surface they cover
# (scanstop_eval's surface_accuracy). Installs the peer itself.
# Usage: bash decimate_bench.sh MESH.ply [WORLD.stl] [ERROR_M] [WORK_DIR]
#   e.g. a run's mesh.ply made with mesh_decimate_error_m:=0 (the raw Marching Cubes mesh), or
#   fuse_map RUN/map raw.ply --decimate 0
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
MESH="${1:?usage: decimate_bench.sh MESH.ply [WORLD.stl] [ERROR_M] [WORK_DIR]}"
WORLD="${2:-}"
ERROR="${3:-0.002}"
WORK="${4:-/tmp/scanstop_decimate_bench}"
mkdir -p "$WORK"
PYTHON="${PYTHON:-/usr/bin/python3}"  # Debian's python3-open3d lives in the system interpreter
if ! "$PYTHON" -c "import open3d" 2>/dev/null; then
  echo "installing the peer: python3-open3d"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO=sudo
  $SUDO apt-get -o DPkg::Lock::Timeout=600 install -y --no-install-recommends python3-open3d >/dev/null
fi
OURS="$(command -v decimate_mesh || catkin_find --first-only scanstop_mesher decimate_mesh 2>/dev/null || true)"
[ -z "$OURS" ] && { echo "decimate_mesh not found: source the devel space that built scanstop_mesher"; exit 1; }

echo "== ours: decimate_mesh --error $ERROR =="
/usr/bin/time -f "wall %e s, peak %M KB" "$OURS" "$MESH" "$WORK/ours.ply" --error "$ERROR" --json 2>"$WORK/ours.time" \
  | tee "$WORK/ours.json"
cat "$WORK/ours.time"
TARGET=$("$PYTHON" -c "import json,sys; print(json.load(open(sys.argv[1]))['faces_after'])" "$WORK/ours.json")
echo "== Open3D: simplify_quadric_decimation to $TARGET triangles =="
/usr/bin/time -f "wall %e s, peak %M KB" "$PYTHON" "$HERE/open3d_decimate.py" "$MESH" "$WORK/open3d.ply" "$TARGET" \
  2>"$WORK/open3d.time"
cat "$WORK/open3d.time"
if [ -n "$WORLD" ]; then
  ACC="$(command -v surface_accuracy || catkin_find --first-only scanstop_eval surface_accuracy 2>/dev/null || true)"
  [ -z "$ACC" ] && { echo "surface_accuracy not found (scanstop_eval): no distances"; exit 0; }
  echo "== against $WORLD (1 cm face samples; covered: visible 5 cm elements within 3 cm) =="
  for m in "$MESH" "$WORK/ours.ply" "$WORK/open3d.ply"; do
    "$ACC" "$WORLD" "$m" --json --quiet | "$PYTHON" -c "
import json, sys
j = json.load(sys.stdin); s = j['surface_distance']
print('%-40s %9d triangles  median %.1f  RMS %.1f  p95 %.1f mm  covered %.1f %%' % (sys.argv[1][-40:], j['triangles'],
      1e3 * s['median_m'], 1e3 * s['rms_m'], 1e3 * s['p95_m'], 100 * j['coverage']['share']))" "$m"
  done
fi
