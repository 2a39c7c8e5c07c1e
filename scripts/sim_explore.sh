#!/usr/bin/env bash
# launch/sim_explore.launch with an exit code a script can use (roslaunch itself always exits 0):
#   0  the mission ended DONE
#   1  the mission ended otherwise (FAILED, ABORTED) after its first scan: summary.json says why
#   2  a start-up error: the launch, or the mission, ended before its first scan (missing world file, a world without
#      floor, a bad start pose, a run_dir of another run or not a directory), named in the FATAL line
#
#   bash scripts/sim_explore.sh [roslaunch arguments, e.g. world:=corridor run_dir:=/tmp/run planes:=100]
#
# Run it after sourcing a devel space; roslaunch starts a master unless ROS_MASTER_URI has one.
# scripts/robot_explore.sh does the same for launch/robot_explore.launch.
set -uo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
world=room_10x8
for a in "$@"; do
  case "$a" in world:=*) world="${a#world:=}" ;; esac
done
# the launch file's default run_dir is per world
exec bash "$here/mission_launch.sh" sim_explore.launch "$HOME/scanstop_runs/$world" "$@"
