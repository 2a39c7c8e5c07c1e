#!/usr/bin/env bash
# launch/sim_explore.launch with an exit code a script can use (roslaunch itself always exits 0):
#   0  the mission ended DONE
#   1  the mission ended otherwise (FAILED, ABORTED): summary.json says why
#   2  the launch ended before the mission did: a start-up error (missing world file, a world without
#      floor, a bad start pose, a run_dir of another run or not a directory), named in the FATAL line
#
#   bash scripts/sim_explore.sh [roslaunch arguments, e.g. world:=corridor run_dir:=/tmp/run planes:=100]
#
# Run it after sourcing a devel space; roslaunch starts a master unless ROS_MASTER_URI has one.
set -uo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
world=room_10x8
run_dir=""
for a in "$@"; do
  case "$a" in
    world:=*) world="${a#world:=}" ;;
    run_dir:=*) run_dir="${a#run_dir:=}" ;;
  esac
done
run_dir="${run_dir:-$HOME/scanstop_runs/$world}"   # the launch file's default
start=$(date +%s)
roslaunch --skip-log-check "$root/launch/sim_explore.launch" "$@"
/usr/bin/python3 "$root/scripts/mission_result.py" "$run_dir" --since "$start"
