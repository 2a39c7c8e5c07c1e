#!/usr/bin/env bash
# Runs a mission launch file of launch/ and exits with the mission's result (scripts/mission_result.py):
# 0 DONE, 1 ended otherwise after a scan, 2 a start-up error (ended before the first scan). Used by sim_explore.sh and
# robot_explore.sh:
#
#   mission_launch.sh LAUNCH_FILE DEFAULT_RUN_DIR [roslaunch arguments]
#
# DEFAULT_RUN_DIR is the launch file's run_dir default (a run_dir:= argument overrides it).
set -uo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
launch_file=$1
run_dir=$2
shift 2
for a in "$@"; do
  case "$a" in run_dir:=*) run_dir="${a#run_dir:=}" ;; esac
done
start=$(date +%s)
roslaunch --skip-log-check "$root/launch/$launch_file" "$@"
/usr/bin/python3 "$root/scripts/mission_result.py" "$run_dir" --since "$start"
