#!/usr/bin/env bash
# Full-resolution exploration benchmark (not part of the test command): runs
# launch/sim_explore.launch headless for each world (default: room_10x8 office_loop corridor
# turtlebot3_house) at 400 planes with the thesis error profile and prints, per world, the scans,
# coverage, collisions, final pose errors, and the compute per cycle (register + plan) next to the
# modelled scan time (target: under 2 s of compute per cycle against 40 s per scan).
#
#   bash scripts/bench_explore.sh [world ...]      (build first: bash scripts/build.sh)
# Environment: SCANSTOP_BENCH_DIR (default runs/bench-<date>-<time>), SCANSTOP_BENCH_ARGS (extra
# roslaunch arguments, e.g. "planes:=100 mesh:=false").
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
export PATH=/usr/bin:$PATH
if [[ ! -f devel/setup.bash ]]; then echo "bench_explore: build first (bash scripts/build.sh)" >&2; exit 1; fi
set +u
# shellcheck disable=SC1091
source devel/setup.bash
set -u
worlds=("$@")
if [[ ${#worlds[@]} -eq 0 ]]; then worlds=(room_10x8 office_loop corridor turtlebot3_house); fi
out="${SCANSTOP_BENCH_DIR:-$root/runs/bench-$(date +%Y%m%d-%H%M%S)}"
mkdir -p "$out"
export ROS_IP=127.0.0.1
unset ROS_HOSTNAME  # it would take precedence over ROS_IP: keep every node on loopback
for w in "${worlds[@]}"; do
  file="$root/worlds/$w.stl"
  if [[ "$w" == turtlebot3_house ]]; then file="$root/../shared/data/worlds/turtlebot3_house.stl"; fi
  port=$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
  echo "bench_explore: $w -> $out/$w"
  # shellcheck disable=SC2086
  ROS_MASTER_URI="http://127.0.0.1:$port" ROS_LOG_DIR="$out/$w/ros_log" roslaunch -p "$port" \
    "$root/launch/sim_explore.launch" world:="$w" world_file:="$file" run_dir:="$out/$w" planes:=400 \
    ${SCANSTOP_BENCH_ARGS:-} > "$out/$w.log" 2>&1 || echo "bench_explore: $w: roslaunch exit $?" >&2
done
/usr/bin/python3 - "$out" "${worlds[@]}" <<'PY'
import json, os, sys
out, worlds = sys.argv[1], sys.argv[2:]
print("\n| world | state | scans | coverage | collisions | SLAM error | odometry error | compute/cycle mean (max) | scan time | mission wall time |")
print("|---|---|---|---|---|---|---|---|---|---|")
for w in worlds:
    p = os.path.join(out, w, "summary.json")
    if not os.path.exists(p):
        print("| %s | no summary (see %s/%s.log) |" % (w, out, w)); continue
    s = json.load(open(p))
    err = lambda k: ("%.1f cm" % (100 * s[k])) if s.get(k) is not None else "-"
    print("| %s | %s | %d | %.1f %% | %d | %s | %s | %.2f s (%.2f s) | %.0f s | %.0f s |" % (
        w, s["state"], s["scans"], 100 * s["coverage"], s["collisions"], err("final_slam_error_m"),
        err("final_odometry_error_m"), s["compute_per_cycle_mean_s"], s["compute_per_cycle_max_s"],
        s["scan_time_mean_s"], s["elapsed_s"]))
PY
