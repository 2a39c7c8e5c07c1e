#!/usr/bin/env bash
# The README's first command (README.md, "The two commands"): sets up a fresh Debian 12 machine (Debian packages), builds the
# workspace, and runs a headless simulated exploration (default: room_10x8, thesis error profile,
# 400 planes per scan) to completion with launch/sim_explore.launch. Prints the mission's progress
# and finally the summary and where the map, the mesh, the images and the report are.
#
#   bash scripts/explore_demo.sh [roslaunch arguments, e.g. world:=office_loop planes:=100 rviz:=true]
#
# Environment: SCANSTOP_RUN_DIR (default runs/<world>-<date>-<time> in the repository),
# SCANSTOP_SKIP_SETUP=1 (no apt), SCANSTOP_SKIP_BUILD=1 (use the existing devel/).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
export PATH=/usr/bin:$PATH   # /usr/bin/python3 has the ROS modules

start=$(date +%s)
if [[ "${SCANSTOP_SKIP_SETUP:-0}" != 1 ]]; then bash scripts/setup.sh; fi
if [[ "${SCANSTOP_SKIP_BUILD:-0}" != 1 ]]; then SCANSTOP_BUILD_TESTS=0 bash scripts/build.sh; fi
if [[ ! -f devel/setup.bash ]]; then
  echo "explore_demo: devel/setup.bash is missing: build first (drop SCANSTOP_SKIP_BUILD)" >&2
  exit 1
fi
set +u
# shellcheck disable=SC1091
source devel/setup.bash
set -u

world=room_10x8
for a in "$@"; do
  case "$a" in world:=*) world="${a#world:=}" ;; esac
done
run_dir="${SCANSTOP_RUN_DIR:-$root/runs/$world-$(date +%Y%m%d-%H%M%S)}"
mkdir -p "$run_dir"

# A private ROS master on a free port over loopback: independent of the host name and of any
# other ROS system running on this machine.
port=$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
export ROS_IP=127.0.0.1 ROS_MASTER_URI="http://127.0.0.1:$port"
unset ROS_HOSTNAME  # it would take precedence over ROS_IP: keep every node on loopback
export ROS_LOG_DIR="$run_dir/ros_log"
echo "explore_demo: exploring $world; run directory $run_dir (ROS logs in $ROS_LOG_DIR)"
set +e
roslaunch -p "$port" --skip-log-check "$root/launch/sim_explore.launch" run_dir:="$run_dir" "$@"
rc=$?
set -e
# roslaunch exits 0 whatever happened: the mission's summary of this launch decides (exit 0 only
# for DONE; scripts/mission_result.py: 1 another end, 2 the launch ended before the mission did).
if [[ ! -f "$run_dir/summary.json" || $(stat -c %Y "$run_dir/summary.json") -lt $start ]]; then
  echo "explore_demo: the mission wrote no summary in this launch (roslaunch exit $rc): it ended before the mission did; see the FATAL line above and $ROS_LOG_DIR" >&2
  exit 2
fi
/usr/bin/python3 - "$run_dir" "$(( $(date +%s) - start ))" <<'PY'
import json, os, sys
run_dir, total = sys.argv[1], int(sys.argv[2])
s = json.load(open(os.path.join(run_dir, "summary.json")))
print("\n==== scanstop exploration: %s ====" % s.get("world", "?"))
print("state            %s%s" % (s["state"], (" (" + s["complete_reason"] + ")") if s.get("complete_reason") else ""))
print("scans            %d, coverage of the reachable floor %.1f %%, collisions %d" % (s["scans"], 100 * s["coverage"], s["collisions"]))
if s.get("ground_truth"):
    print("final pose error SLAM %.1f cm / %.2f deg, odometry alone %.1f cm / %.1f deg" % (
        100 * s["final_slam_error_m"], s["final_slam_error_yaw_deg"], 100 * s["final_odometry_error_m"], s["final_odometry_error_yaw_deg"]))
if s.get("ate_rms_m") is not None:
    print("pose error, every scan  SLAM RMS %.1f cm, max %.1f cm (scan %d); odometry alone RMS %.1f cm" % (
        100 * s["ate_rms_m"], 100 * s["ate_max_m"], s["ate_max_scan"], 100 * s["odometry_ate_rms_m"]))
if s.get("min_clearance_m") is not None:
    print("true clearance   smallest %.1f cm; %d of %d straight legs closer than 5 cm" % (
        100 * s["min_clearance_m"], s["legs_closer_than_5cm"], s["legs_measured"]))
print("compute / cycle  %.2f s mean, %.2f s max (modelled scan time %.1f s)" % (
    s["compute_per_cycle_mean_s"], s["compute_per_cycle_max_s"], s["scan_time_mean_s"]))
print("time             %.0f s mission, %d s with setup and build" % (s["elapsed_s"], total))
print("map              %s/map (poses.csv, scans/*.pcd)" % run_dir)
for f in ("mesh.ply", "mesh.stl"):
    if os.path.exists(os.path.join(run_dir, f)):
        print("mesh             %s/%s" % (run_dir, f))
print("images           %s/explorer (per step), report_coverage.png, report_trajectory.png, report_pose_error.png" % run_dir)
print("report           %s/report.html, report.md, summary.json" % run_dir)
print("view it          roslaunch launch/view_run.launch run_dir:=%s" % run_dir)
sys.exit(0 if s["state"] == "DONE" else 1)
PY
