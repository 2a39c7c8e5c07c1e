#!/bin/bash
# Ball Pivoting benchmark: ours next to Open3D (python3-open3d) and MeshLab (meshlabserver under
# xvfb-run) on the same points (the Stanford bunny's vertices with normals) and radii (one and
# three), then a 21-scan simulated room map (room_10x8, 400 planes, thesis errors, 1 cm voxels).
# Installs the peers itself. Usage: bash run_bench.sh [WORK_DIR]   (after sourcing a devel space
# with scanstop_mesher; the room part also needs scanstop_sim's scan_world)
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
WORK="${1:-/tmp/scanstop_bpa_bench}"
mkdir -p "$WORK"
PYTHON="${PYTHON:-/usr/bin/python3}"  # Debian's python3-open3d lives in the system interpreter

need=()
"$PYTHON" -c "import open3d" 2>/dev/null || need+=(python3-open3d)
command -v meshlabserver >/dev/null || need+=(meshlab)
command -v xvfb-run >/dev/null || need+=(xvfb xauth)
if [ ${#need[@]} -gt 0 ]; then
  echo "installing the peers: ${need[*]}"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO=sudo
  $SUDO apt-get -o DPkg::Lock::Timeout=600 install -y --no-install-recommends "${need[@]}" >/dev/null
fi

BENCH="$(command -v bpa_bench || true)"
[ -z "$BENCH" ] && BENCH="$(catkin_find --first-only scanstop_mesher bpa_bench 2>/dev/null || true)"
[ -z "$BENCH" ] && { echo "bpa_bench not found: source the devel space that built scanstop_mesher"; exit 1; }
REF="${SCANSTOP_SHARED_DATA:-$HERE/../../../../shared/data}/bunny/bun_zipper.ply"
POINTS="$WORK/bunny_points.ply"

echo "== Stanford bunny =="
"$BENCH" bunny --ply "$REF" --points-out "$POINTS" --repeat 5
for radii in 0.0012 0.0012,0.0024,0.0048; do
  "$PYTHON" "$HERE/open3d_bpa.py" "$POINTS" "$radii" 3 "$WORK/open3d_$radii.ply"
  echo -n "  Open3D mesh: "; "$BENCH" analyze "$WORK/open3d_$radii.ply" "$REF"
done

# MeshLab: one filter per radius (its Ball Pivoting continues on the faces of the earlier pass).
# meshlabserver reports no filter times: a run with 6 repetitions of the passes (each starting
# afresh, DeleteFaces) minus a run with 1, divided by 5, is the time of the passes alone.
mlx() {  # radii reps
  echo '<!DOCTYPE FilterScript>'
  echo '<FilterScript>'
  for _ in $(seq "$2"); do
    local first=true
    for r in ${1//,/ }; do
      cat <<XML
 <filter name="Surface Reconstruction: Ball Pivoting">
  <Param type="RichAbsPerc" value="$r" min="0" max="0.3" name="BallRadius"/>
  <Param type="RichFloat" value="20" name="Clustering"/>
  <Param type="RichFloat" value="90" name="CreaseThr"/>
  <Param type="RichBool" value="$first" name="DeleteFaces"/>
 </filter>
XML
      first=false
    done
  done
  echo '</FilterScript>'
}
best_time() {  # best wall time of 3 runs of "$@"
  local best=""
  for _ in 1 2 3; do
    local t0 t1
    t0=$(date +%s.%N); "$@" >/dev/null 2>&1; t1=$(date +%s.%N)
    best=$("$PYTHON" -c "b='$best'; t=$t1-$t0; print(t if b=='' else min(float(b), t))")
  done
  echo "$best"
}
for radii in 0.0012 0.0012,0.0024,0.0048; do
  mlx "$radii" 1 > "$WORK/bpa_$radii.mlx"
  mlx "$radii" 6 > "$WORK/bpa6_$radii.mlx"
  out="$WORK/meshlab_$radii.ply"
  t1=$(best_time xvfb-run -a meshlabserver -i "$POINTS" -o "$out" -s "$WORK/bpa_$radii.mlx")
  t6=$(best_time xvfb-run -a meshlabserver -i "$POINTS" -o "$WORK/meshlab6.ply" -s "$WORK/bpa6_$radii.mlx")
  if [ ! -s "$out" ]; then echo "MeshLab failed for radii $radii"; continue; fi
  printf "%-34s %9.3f s (runs with 1 and 6 repetitions: %.3f s, %.3f s)\n" "MeshLab 2020.09 radii ${radii//,/ }" \
    "$("$PYTHON" -c "print(max(0.0, ($t6 - $t1) / 5))")" "$t1" "$t6"
  echo -n "  MeshLab mesh: "; "$BENCH" analyze "$out" "$REF"
done

echo "== 21-scan simulated room map (room_10x8) =="
SCAN_WORLD="$(command -v scan_world || catkin_find --first-only scanstop_sim scan_world 2>/dev/null || true)"
WORLD="$HERE/../../../worlds/room_10x8.stl"
if [ -z "$SCAN_WORLD" ] || [ ! -f "$WORLD" ]; then
  echo "skipped: scanstop_sim's scan_world or worlds/room_10x8.stl not found"
  exit 0
fi
rm -rf "$WORK/room_map"; mkdir -p "$WORK/room_scans"
: > "$WORK/room_scans/list.txt"
i=0
for y in 0.9 3.4 7.0; do
  for x in 1.0 2.4 3.8 5.0 6.4 7.6 8.6; do
    f=$(printf "%s/room_scans/scan_%02d.pcd" "$WORK" $i)
    [ -s "$f" ] || "$SCAN_WORLD" "$WORLD" "$f" --pose "$x,$y,0" --planes 400 --profile thesis --seed $((i + 1)) >/dev/null
    echo "$f $x $y 0 0.45" >> "$WORK/room_scans/list.txt"
    i=$((i + 1))
  done
done
"$BENCH" make_map "$WORK/room_map" "$WORK/room_scans/list.txt"
"$BENCH" map "$WORK/room_map" --voxel 0.01 --out "$WORK/room_mesh.ply"
