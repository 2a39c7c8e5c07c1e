#!/usr/bin/env bash
# Soak benchmark (not part of the test command): a long simulated exploration of the largest world
# (default: the real house, ../shared/data/worlds/turtlebot3_house.stl, 50 planes, a budget of 100
# scans, the thesis' knowledge radius of 1 m so that the house takes that many scans; with the
# default 2.5 m it is explored in 13) with launch/sim_explore.launch, sampling the resident memory (RSS) of every node after each
# scan. Prints the time per scan, each node's memory at the start (baseline: after the node came
# up, before the first scan), every 10 scans, at the end of the mission and 10 s after it (all
# nodes kept up), and the growth per scan. Writes soak.csv (one row per scan) into the run directory.
#
#   bash scripts/soak.sh [roslaunch arguments, e.g. world:=office_loop max_scans:=50 planes:=100]
# Environment: SCANSTOP_SOAK_DIR (default runs/soak-<date>-<time>), SCANSTOP_DEVEL (default devel,
# the workspace's devel space; build first: bash scripts/build.sh).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
export PATH=/usr/bin:$PATH
devel="${SCANSTOP_DEVEL:-$root/devel}"
if [[ ! -f "$devel/setup.bash" ]]; then echo "soak: $devel/setup.bash is missing: build first (bash scripts/build.sh)" >&2; exit 1; fi
set +u
# shellcheck disable=SC1090
source "$devel/setup.bash"
set -u
out="${SCANSTOP_SOAK_DIR:-$root/runs/soak-$(date +%Y%m%d-%H%M%S)}"
mkdir -p "$out"
house="$root/../shared/data/worlds/turtlebot3_house.stl"
port=$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
export ROS_IP=127.0.0.1 ROS_MASTER_URI="http://127.0.0.1:$port" ROS_LOG_DIR="$out/ros_log"
echo "soak: run directory $out"
roslaunch -p "$port" --skip-log-check "$root/launch/sim_explore.launch" world:=turtlebot3_house world_file:="$house" \
  planes:=50 max_scans:=100 knowledge_radius:=1.0 run_dir:="$out" shutdown_when_done:=false "$@" > "$out/roslaunch.log" 2>&1 &
launch_pid=$!
cleanup() { kill -INT "$launch_pid" 2>/dev/null || true; wait "$launch_pid" 2>/dev/null || true; }
trap cleanup EXIT

/usr/bin/python3 - "$out" "$launch_pid" <<'PY'
import csv, os, sys, time
import yaml

out, launch_pid = sys.argv[1], int(sys.argv[2])
NODES = ["sim_node", "icp_slam_node", "explorer_node", "bpa_mesher_node", "mission_node"]

def children(pid):
    kids = []
    for d in os.listdir("/proc"):
        if d.isdigit():
            try:
                stat = open("/proc/%s/stat" % d).read()
            except OSError:
                continue
            if int(stat[stat.rindex(")") + 2:].split()[1]) == pid:
                kids.append(int(d))
    return kids

def node_pids():
    pids = {}
    for pid in children(launch_pid):
        try:
            cmd = open("/proc/%d/cmdline" % pid, "rb").read().split(b"\0")
        except OSError:
            continue
        for a in cmd:
            if a.startswith(b"__name:="):
                pids[a[8:].decode()] = pid
    return pids

def rss_mb(pid):
    try:
        for line in open("/proc/%d/status" % pid):
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return float("nan")

def sample():
    pids = node_pids()
    return {n: rss_mb(pids[n]) if n in pids else float("nan") for n in NODES}

def state():
    try:
        with open(os.path.join(out, "mission_state.yaml")) as f:
            s = yaml.safe_load(f) or {}
        return s.get("state", ""), len(s.get("scans") or [])
    except (OSError, yaml.YAMLError):
        return "", 0

t0 = time.time()
# Baseline: every node up, before the first scan is registered.
while len(node_pids()) < len(NODES) and time.time() - t0 < 120:
    time.sleep(0.5)
time.sleep(3.0)
baseline = sample()
rows, last_n, last_t = [], 0, time.time()
while True:
    st, n = state()
    if n != last_n:
        now = time.time()
        rows.append(dict(scan=n, t_s=now - t0, dt_s=(now - last_t) / max(1, n - last_n), **sample()))
        last_n, last_t = n, now
    if st in ("DONE", "FAILED", "ABORTED"):
        break
    if not os.path.exists("/proc/%d" % launch_pid):
        print("soak: roslaunch ended early; see %s/roslaunch.log" % out)
        break
    time.sleep(0.5)
end = sample()
time.sleep(10.0)
after = sample()
with open(os.path.join(out, "soak.csv"), "w") as f:
    w = csv.DictWriter(f, fieldnames=["scan", "t_s", "dt_s"] + NODES)
    w.writeheader()
    w.writerows(rows)

def fmt(d):
    return " | ".join("%.1f" % d[n] for n in NODES)

print("\nsoak: %s, %d scans, mission %s, %.0f s" % (out, last_n, st, time.time() - t0))
print("\n| moment | " + " | ".join(NODES) + " |  (RSS, MB)")
print("|---|" + "---|" * len(NODES))
print("| baseline (before scan 1) | %s |" % fmt(baseline))
for r in rows:
    if r["scan"] in (1, 2) or r["scan"] % 10 == 0 or r is rows[-1]:
        print("| after scan %d (%.0f s) | %s |" % (r["scan"], r["t_s"], fmt(r)))
print("| mission end | %s |" % fmt(end))
print("| 10 s after the end | %s |" % fmt(after))
if len(rows) > 2:
    dts = sorted(r["dt_s"] for r in rows[1:])
    print("\ntime per scan (wall, 50-plane scans are modelled, not waited for): mean %.2f s, median %.2f s, max %.2f s"
          % (sum(dts) / len(dts), dts[len(dts) // 2], dts[-1]))
    first, last = rows[0], rows[-1]
    span = max(1, last["scan"] - first["scan"])
    print("growth per scan from scan %d to %d: %s MB" % (first["scan"], last["scan"], ", ".join(
        "%s %+.2f" % (n, (last[n] - first[n]) / span) for n in NODES)))
    print("after the run vs baseline: %s MB" % ", ".join("%s %+.1f" % (n, after[n] - baseline[n]) for n in NODES))
if os.path.exists(os.path.join(out, "summary.json")):
    import json
    s = json.load(open(os.path.join(out, "summary.json")))
    print("summary: state %s, scans %d, coverage %.1f %%, collisions %d, complete %s (%s)" % (
        s["state"], s["scans"], 100 * s["coverage"], s["collisions"], s.get("complete"), s.get("complete_reason", "")))
PY
