#!/usr/bin/env bash
# Acceptance check (issue: mission, "rosbag"): a recorded mission replayed with replay.launch
# rebuilds the same map. Runs a short simulated exploration of room_10x8 with record:=true
# (PLANES planes, MAX_SCANS scans), then plays run_dir/mission.bag into icp_slam_node with
# src/scanstop_slam/launch/replay.launch and compares the rebuilt map directory with the run's:
# the same number of scans, every scan pose within TOL_M metres and TOL_DEG degrees, and the same
# number of points per scan. Also: the mission left report.html and its plots (make_report.py).
# Usage: bash scripts/check_mission_replay.sh [WORK_DIR]   (after sourcing a devel space; exit 0 = pass)
set -uo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
work="${1:-$(mktemp -d /tmp/check_mission_replay.XXXXXX)}"
planes=${PLANES:-50}; max_scans=${MAX_SCANS:-4}; tol_m=${TOL_M:-0.005}; tol_deg=${TOL_DEG:-0.05}
mkdir -p "$work"
port=$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
export ROS_IP=127.0.0.1 ROS_MASTER_URI="http://127.0.0.1:$port" ROS_LOG_DIR="$work/ros_log"
unset ROS_HOSTNAME
run="$work/run"; replay="$work/replay_map"
rm -rf "$run" "$replay"

echo "check_mission_replay: exploring room_10x8 ($planes planes, $max_scans scans, record:=true) into $run"
timeout 600 roslaunch -p "$port" --skip-log-check "$root/launch/sim_explore.launch" run_dir:="$run" \
  planes:="$planes" max_scans:="$max_scans" mesh:=false record:=true > "$work/explore.log" 2>&1
if [[ ! -f "$run/summary.json" || ! -s "$run/map/poses.csv" ]]; then
  echo "check_mission_replay: the mission left no summary or map (see $work/explore.log)"; tail -30 "$work/explore.log"; exit 1
fi
# In simulation the summary holds the ground-truth coverage (the map against the world's truly
# reachable floor), next to the explorer's own figure.
if ! /usr/bin/python3 - "$run/summary.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
tc, area = s.get("true_coverage"), s.get("true_reachable_floor_m2")
sc, visible = s.get("surface_coverage"), s.get("surface_visible_elements")
print("check_mission_replay: coverage %s (explorer's map), true coverage %s of %s m2, visible surface held %s of %s "
      "elements" % (s["coverage"], tc, area, sc, visible))
# The surface: a short run holds some of the room's visible surface (104,621 5 cm elements at 100 planes).
sys.exit(0 if isinstance(tc, float) and 0.2 < tc <= 1.0 and 90.0 < area < 100.0 and isinstance(sc, float) and
         0.1 < sc <= 1.0 and isinstance(visible, int) and 50000 < visible < 400000 else 1)
PY
then
  echo "check_mission_replay: summary.json has no plausible true_coverage (room_10x8: 96 m2 of reachable floor) or surface_coverage"; exit 1
fi
# The mission ends with make_report.py (html_report): report.html, its plots and the explorer's
# georeferenced floor map they draw on, linked from report.md.
for f in report.html report_coverage.png report_trajectory.png report_pose_error.png explorer/floor_map.yaml; do
  [[ -s "$run/$f" ]] || { echo "check_mission_replay: no $run/$f"; cat "$run/make_report.log" 2>/dev/null; exit 1; }
done
grep -q "(report.html)" "$run/report.md" || { echo "check_mission_replay: report.md does not link report.html"; exit 1; }
echo "check_mission_replay: report.html and its plots are there"
# rosbag record closes the bag on SIGINT; the launch ends when the mission does.
for _ in $(seq 30); do [[ -f "$run/mission.bag" ]] && break; sleep 1; done
[[ -f "$run/mission.bag" ]] || { echo "check_mission_replay: no $run/mission.bag"; ls -la "$run"; exit 1; }
scans=$(($(wc -l < "$run/map/poses.csv") - 1))
echo "check_mission_replay: the run registered $scans scans; replaying $run/mission.bag"

roslaunch -p "$port" --skip-log-check "$root/src/scanstop_slam/launch/replay.launch" bag:="$run/mission.bag" \
  map_dir:="$replay" > "$work/replay.log" 2>&1 &
replay_pid=$!
trap 'kill -INT $replay_pid 2>/dev/null' EXIT
# The launch keeps running after the bag: wait until the replayed map lists every scan.
for _ in $(seq 300); do
  [[ -f "$replay/poses.csv" && $(($(wc -l < "$replay/poses.csv") - 1)) -ge $scans ]] && break
  kill -0 $replay_pid 2>/dev/null || break
  sleep 1
done
sleep 2
kill -INT $replay_pid 2>/dev/null; wait $replay_pid 2>/dev/null
trap - EXIT

/usr/bin/python3 - "$run/map" "$replay" "$tol_m" "$tol_deg" <<'PY'
import csv, math, os, sys
run, rep, tol_m, tol_deg = sys.argv[1], sys.argv[2], float(sys.argv[3]), float(sys.argv[4])
def load(d):
    p = os.path.join(d, "poses.csv")
    if not os.path.exists(p):
        return []
    return list(csv.DictReader(open(p)))
def points(d, row):
    # PCD header: POINTS n
    with open(os.path.join(d, row["file"]), "rb") as f:
        for line in f:
            if line.startswith(b"POINTS"):
                return int(line.split()[1])
    return -1
a, b = load(run), load(rep)
print("scan  run (x, y, yaw deg)              replay (x, y, yaw deg)           diff mm  diff deg  points run/replay")
ok = len(a) == len(b) and len(a) > 1
if len(a) != len(b):
    print("scan counts differ: run %d, replay %d" % (len(a), len(b)))
for ra, rb in zip(a, b):
    dx = float(ra["map_x"]) - float(rb["map_x"]); dy = float(ra["map_y"]) - float(rb["map_y"])
    dyaw = math.degrees(math.atan2(math.sin(float(ra["map_yaw"]) - float(rb["map_yaw"])), math.cos(float(ra["map_yaw"]) - float(rb["map_yaw"]))))
    d = math.hypot(dx, dy)
    na, nb = points(run, ra), points(rep, rb)
    good = d <= tol_m and abs(dyaw) <= tol_deg and na == nb
    ok = ok and good
    print("%4s  (%7.3f %7.3f %8.2f)   (%7.3f %7.3f %8.2f)   %7.2f  %8.4f  %d/%d%s" % (
        ra["index"], float(ra["map_x"]), float(ra["map_y"]), math.degrees(float(ra["map_yaw"])),
        float(rb["map_x"]), float(rb["map_y"]), math.degrees(float(rb["map_yaw"])), 1000 * d, dyaw, na, nb,
        "" if good else "   <-- differs"))
print("check_mission_replay: %s (%d scans; tolerance %.1f mm, %.3f deg)" % (
    "the replay rebuilt the same map" if ok else "FAILED", len(a), 1000 * tol_m, tol_deg))
sys.exit(0 if ok else 1)
PY
