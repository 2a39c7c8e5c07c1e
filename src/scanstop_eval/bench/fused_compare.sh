#!/usr/bin/env bash
# The fused map's measured comparison, OctoMap against our TSDF (issue #20 point 1), on the same scans:
#   bash src/scanstop_eval/bench/fused_compare.sh OUT_DIR [MAP_DIR WORLD.stl START]...
# Always: artifacts_room (thesis chapter 8) scanned at ten true poses of its room, door and corridor
# (400 planes, thesis errors, mixed pixels, the world's materials: a retroreflective table leg, an
# absorbing monitor) into OUT_DIR/artifacts_map. Then every MAP_DIR given (a simulated run's map, in the
# frame of its start pose START = x,y,yaw in WORLD.stl, or - for the world's documented start). Prints fused_map_compare's table for each
# (kept in OUT_DIR/NAME.txt).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)"
export PATH="/usr/bin:$PATH"
if [ $# -lt 1 ] || [ $(( ($# - 1) % 3 )) -ne 0 ]; then
  echo "usage: fused_compare.sh OUT_DIR [MAP_DIR WORLD.stl START]..." >&2
  exit 2
fi
OUT="$1"
shift
DEVEL="$ROOT/devel/lib"
SCAN_WORLD="$DEVEL/scanstop_sim/scan_world"
COMPARE="$DEVEL/scanstop_eval/fused_map_compare"
for exe in "$SCAN_WORLD" "$COMPARE"; do
  [ -x "$exe" ] || { echo "fused_compare: $exe is missing: build the workspace first (catkin_make)" >&2; exit 1; }
done
mkdir -p "$OUT/artifacts_map/scans"

# The artifacts room at true poses, in the map frame of the first one (1.5, 1.5, 0 in the world).
WORLD="$ROOT/worlds/artifacts_room.stl"
POSES=("1.5,1.5,0.0" "3.0,1.0,0.5" "5.0,1.2,2.0" "1.5,3.2,-1.0" "5.2,4.2,3.0" "2.5,4.3,1.0" "2.95,0.6,-1.57"
       "2.95,-0.75,0.0" "1.0,-0.75,0.0" "5.0,-0.75,3.14")
CSV="$OUT/artifacts_map/poses.csv"
echo "index,file,stamp_s,map_x,map_y,map_yaw,odom_x,odom_y,odom_yaw,sensor_x,sensor_y,sensor_z,converged,iterations,correspondences,rms_m,overlap" > "$CSV"
for i in "${!POSES[@]}"; do
  file=$(printf "scans/scan_%04d.pcd" "$i")
  "$SCAN_WORLD" "$WORLD" "$OUT/artifacts_map/$file" --pose "${POSES[$i]}" --planes 400 --profile thesis \
    --mixed-pixels --seed $((7 + i)) > /dev/null
  IFS=, read -r x y yaw <<< "${POSES[$i]}"
  x=$(awk "BEGIN{print $x - 1.5}"); y=$(awk "BEGIN{print $y - 1.5}")  # in the frame of the first pose
  echo "$i,$file,$((i * 60)).0,$x,$y,$yaw,$x,$y,$yaw,0,0,0.45,1,0,0,0,1" >> "$CSV"
done

run() {  # NAME MAP WORLD START
  echo "== $1"
  local start=()
  [ "$4" = "-" ] || start=(--start "$4")
  "$COMPARE" "$3" "$2" "${start[@]}" --quiet | tee "$OUT/$1.txt"
}
run artifacts_room "$OUT/artifacts_map" "$WORLD" 1.5,1.5,0
while [ $# -gt 0 ]; do
  run "$(basename "$(dirname "$(realpath "$1")")")" "$1" "$2" "$3"
  shift 3
done
