#!/usr/bin/env bash
# launch/robot_explore.launch with an exit code a script can use (roslaunch itself always exits 0):
#   0  the mission ended DONE
#   1  the mission ended otherwise (FAILED, ABORTED) after its first scan: summary.json says why
#   2  a start-up error: the launch, or the mission, ended before its first scan (a serial device missing or not
#      answering, a run_dir of another run or not a directory), named in the FATAL line
#
#   bash scripts/robot_explore.sh [roslaunch arguments, e.g. pioneer_port:=/dev/ttyUSB0 planes:=100]
#
# Run it after sourcing a devel space; roslaunch starts a master unless ROS_MASTER_URI has one.
set -uo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
exec bash "$here/mission_launch.sh" robot_explore.launch "$HOME/scanstop_runs/robot" "$@"
