#!/bin/bash
# ICP benchmark: (a) the real room pair (../shared/data/rooms, scan2 -> scan1 from the published
# initial guess) at c_max 0.5 and 0.1 m: our 6dof ICP (icp_register), Open3D's point-to-point
# registration_icp (python3-open3d) and PCL's IterativeClosestPoint (pcl_icp_bench), all with at
# most 100 iterations on the full clouds; our point-to-plane ICP (its time includes building the
# voxel map with its normals) next to Open3D's (its time includes estimating the target's normals); (b) ICP SLAM on 21 full 400-plane simulated scans of
# room_10x8 (thesis errors): each registered against all before it (slam_bench).
# Installs Open3D itself if missing. Usage: bash slam_bench.sh [WORK_DIR]  (after sourcing a devel
# space with scanstop_slam; part (b) also needs scanstop_sim's scan_world)
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
WORK="${1:-/tmp/scanstop_slam_bench}"
mkdir -p "$WORK"
PYTHON="${PYTHON:-/usr/bin/python3}"  # Debian's python3-open3d lives in the system interpreter
if ! "$PYTHON" -c "import open3d" 2>/dev/null; then
  echo "installing python3-open3d"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO=sudo
  $SUDO apt-get -o DPkg::Lock::Timeout=600 install -y python3-open3d >/dev/null
fi
find_exe() { command -v "$1" || catkin_find --first-only scanstop_slam "$1" 2>/dev/null || true; }
REG="$(find_exe icp_register)"; PCL_ICP="$(find_exe pcl_icp_bench)"; SLAM="$(find_exe slam_bench)"
O3D="$HERE/open3d_icp.py"; [ -f "$O3D" ] || O3D="$(find_exe open3d_icp.py)"
for e in "$REG" "$PCL_ICP" "$SLAM"; do
  [ -n "$e" ] || { echo "icp_register, pcl_icp_bench or slam_bench not found: source the devel space that built scanstop_slam"; exit 1; }
done
DATA="${SCANSTOP_SHARED_DATA:-$HERE/../../../../shared/data}"
T="$DATA/rooms/room_scan1.pcd"; S="$DATA/rooms/room_scan2.pcd"
[ -f "$T" ] && [ -f "$S" ] || { echo "room pair not found under $DATA/rooms (set SCANSTOP_SHARED_DATA)"; exit 1; }
# Published initial guess of scan2 -> scan1: yaw 0.6931 rad, translation (1.79387, 0.720047, 0).
INIT="1.79387,0.720047,0,$("$PYTHON" -c 'import math; print(repr(math.degrees(0.6931)))')"

echo "== (a) room pair scan2 -> scan1 ($(nproc) cores; Open3D $("$PYTHON" -c 'import open3d; print(open3d.__version__)')) =="
row() {  # name json [reference json]
  "$PYTHON" - "$1" "$2" "${3:-}" <<'PY'
import json, math, sys
name, r = sys.argv[1], json.loads(sys.argv[2])
t, q = r["translation"], r["quaternion"]
diff = ""
if sys.argv[3]:
    o = json.loads(sys.argv[3])
    dt = math.dist(t, o["translation"])
    dot = abs(sum(a * b for a, b in zip(q, o["quaternion"])))
    diff = "  vs Open3D: %.1f mm, %.3f deg" % (dt * 1000, math.degrees(2 * math.acos(min(1.0, dot))))
it = r.get("iterations", "-")
print("  %-14s %7.2f s  iters %4s  t = (%.4f, %.4f, %.4f) m  yaw %.4f deg  rms %.4f m%s"
      % (name, r["time_s"], it, t[0], t[1], t[2], math.degrees(r["yaw"]), r["rms"], diff))
PY
}
for c in 0.5 0.1; do
  echo "c_max = $c m, at most 100 iterations:"
  o=$("$PYTHON" "$O3D" "$T" "$S" --init "$INIT" --c-max "$c" --max-iterations 100)
  ours=$("$REG" "$T" "$S" --init "$INIT" --mode 6dof --c-max "$c" --max-iterations 100 --json || true)
  pcl=$("$PCL_ICP" "$T" "$S" --init "$INIT" --c-max "$c" --max-iterations 100)
  row "ours 6dof" "$ours" "$o"
  row "Open3D" "$o"
  row "PCL" "$pcl" "$o"
  o_plane=$("$PYTHON" "$O3D" "$T" "$S" --init "$INIT" --c-max "$c" --max-iterations 100 --method point_to_plane)
  ours_plane=$("$REG" "$T" "$S" --init "$INIT" --mode 6dof --c-max "$c" --max-iterations 100 --method point_to_plane --json || true)
  row "ours p2plane" "$ours_plane" "$o_plane"
  row "Open3D p2plane" "$o_plane"
done
# Converged to the tolerance (the reference of the gtest IcpRealData.RoomPairAgreesWithOpen3D).
echo "c_max = 0.5 m, to convergence (Open3D: relative fitness/RMSE 1e-12, 300 iterations; ours: t_c 1e-7 m, r_c 1e-5 deg):"
o=$("$PYTHON" "$O3D" "$T" "$S" --init "$INIT" --c-max 0.5 --max-iterations 300 --relative 1e-12)
ours=$("$REG" "$T" "$S" --init "$INIT" --mode 6dof --c-max 0.5 --max-iterations 1000 --t-c 1e-7 --r-c-deg 1e-5 --json || true)
row "ours 6dof" "$ours" "$o"
row "Open3D" "$o"
echo "  Open3D JSON: $o"
o_plane=$("$PYTHON" "$O3D" "$T" "$S" --init "$INIT" --c-max 0.5 --max-iterations 300 --relative 1e-12 --method point_to_plane)
ours_plane=$("$REG" "$T" "$S" --init "$INIT" --mode 6dof --c-max 0.5 --max-iterations 1000 --t-c 1e-7 --r-c-deg 1e-5 --method point_to_plane --json || true)
row "ours p2plane" "$ours_plane" "$o_plane"
row "Open3D p2plane" "$o_plane"
echo "  ours p2plane JSON: $ours_plane"
echo "  Open3D p2plane JSON: $o_plane"

echo "== (b) ICP SLAM: 21 full 400-plane scans of room_10x8 (thesis errors) =="
SCAN_WORLD="$(command -v scan_world || catkin_find --first-only scanstop_sim scan_world 2>/dev/null || true)"
WORLD="$HERE/../../../worlds/room_10x8.stl"
if [ -z "$SCAN_WORLD" ] || [ ! -f "$WORLD" ]; then
  echo "skipped: scanstop_sim's scan_world or worlds/room_10x8.stl not found"
  exit 0
fi
mkdir -p "$WORK/room_scans"
LIST="$WORK/room_scans/list.txt"; : > "$LIST"
i=0
for y in 0.9 3.4 7.0; do  # a snake through the room, legs of 1.0-1.4 m and row changes of 2.5-3.6 m
  xs="1.0 2.4 3.8 5.0 6.4 7.6 8.6"; [ "$y" = 3.4 ] && xs="8.6 7.6 6.4 5.0 3.8 2.4 1.0"
  for x in $xs; do
    yaw=$("$PYTHON" -c "print(round(0.3 * ($i % 5) - 0.6, 2))")
    f=$(printf "%s/room_scans/scan_%02d.pcd" "$WORK" $i)
    [ -s "$f" ] || "$SCAN_WORLD" "$WORLD" "$f" --pose "$x,$y,$yaw" --planes 400 --profile thesis --seed $((i + 1)) >/dev/null
    echo "$f $x $y $yaw" >> "$LIST"
    i=$((i + 1))
  done
done
for mode in 3dof 6dof; do "$SLAM" "$LIST" --mode $mode; done
