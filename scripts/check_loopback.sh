#!/usr/bin/env bash
# Checks that the simulated setup binds to the loopback address: starts launch/sim.launch with the
# environment the scripts use (ROS_IP=127.0.0.1) and lists every listening TCP socket of the master,
# roslaunch and the nodes. The master (XML-RPC), roslaunch and every TCPROS server must listen on
# 127.0.0.1 only. roscpp's XML-RPC slave server (xmlrpcpp) always binds all interfaces, whatever
# ROS_IP says; it is reported as a known exception (docs/reliability.md, "Security: ROS 1 has no authentication"), and any other socket on a
# non-loopback address fails the check.
# Usage: bash scripts/check_loopback.sh   (after sourcing a devel space; exit 0 = pass)
set -uo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
port=${SCANSTOP_LOOPBACK_PORT:-11397}
export ROS_IP=127.0.0.1 ROS_MASTER_URI="http://127.0.0.1:$port"
unset ROS_HOSTNAME
log=$(mktemp /tmp/check_loopback.XXXXXX.log)
export ROS_LOG_DIR=$(mktemp -d /tmp/check_loopback.XXXXXX)
roslaunch -p "$port" --skip-log-check "$root/launch/sim.launch" > "$log" 2>&1 &
launch_pid=$!
cleanup() {
  kill -INT "$launch_pid" 2>/dev/null
  for _ in $(seq 20); do kill -0 "$launch_pid" 2>/dev/null || break; sleep 0.5; done
  kill -KILL "$launch_pid" 2>/dev/null; wait "$launch_pid" 2>/dev/null
  rm -rf "$ROS_LOG_DIR" "$log"
}
trap cleanup EXIT
# Wait until sim_node serves (its services exist), at most 120 s of wall time (3.7 s on a quiet
# machine; a CI run beside other heavy jobs once needed more than 60).
deadline=$((SECONDS + 120))
while (( SECONDS < deadline )); do
  rosservice list 2>/dev/null | grep -q "/take_scan" && break
  sleep 1
done
if ! rosservice list 2>/dev/null | grep -q "/take_scan"; then
  echo "check_loopback: sim.launch did not come up within 120 s; its output:"; cat "$log"; exit 1
fi
# PIDs of roslaunch and everything it started; the XML-RPC ports of the nodes (from the master).
pids=" $launch_pid $(pgrep -P "$launch_pid" | tr '\n' ' ') "
xmlrpc_ports=" $(/usr/bin/python3 -c '
import rosgraph, sys
from urllib.parse import urlparse
m = rosgraph.Master("/check_loopback")
names = set(n for kind in m.getSystemState() for _, ns in kind for n in ns)
print(" ".join(str(urlparse(m.lookupNode(n)).port) for n in sorted(names) if n != "/check_loopback"))
') "
fail=0; seen=0
while read -r _ _ _ local _ users; do
  pid=$(sed -n 's/.*pid=\([0-9]*\).*/\1/p' <<< "$users")
  name=$(sed -n 's/.*(("\([^"]*\)".*/\1/p' <<< "$users")
  [[ -n "$pid" && "$pids" == *" $pid "* ]] || continue
  seen=$((seen + 1))
  addr=${local%:*}
  if [[ "$addr" == 127.* || "$addr" == "[::1]" ]]; then
    echo "loopback  $local  $name"
  elif [[ "$name" != "rosmaster" && "$name" != "roslaunch" && "$xmlrpc_ports" == *" ${local##*:} "* ]]; then
    echo "all       $local  $name  (roscpp XML-RPC slave API: known exception, xmlrpcpp ignores ROS_IP)"
  else
    echo "EXPOSED   $local  $name"
    fail=1
  fi
done < <(ss -ltnpH)
if [[ $seen -lt 3 ]]; then echo "check_loopback: found only $seen listening sockets of the launch"; exit 1; fi
[[ $fail -eq 0 ]] && echo "check_loopback: master, roslaunch and TCPROS listen on loopback only" ||
  echo "check_loopback: some server listens on a non-loopback address (see EXPOSED)"
exit $fail
