#!/usr/bin/env bash
# Full-resolution exploration benchmark (not part of the test command): runs
# launch/sim_explore.launch headless for each world (default: room_10x8 office_loop corridor
# turtlebot3_house furnished_1..3 office_large; office_large takes 5-15 min of wall time) at 400 planes with the thesis error profile and prints, per world, the scans,
# coverage, collisions, the pose error of every scan against ground truth (ATE RMS and max, SLAM and
# odometry alone) and the final one, the body's smallest true clearance and the legs closer than
# 5 cm, and the compute per cycle (register + plan) next to the
# modelled scan time (target: under 2 s of compute per cycle against 40 s per scan). The default list
# also runs room_10x8 with min_scan_travel 2.0, the issue's acceptance run (<= 21 scans, >= 95 % of
# the reachable floor, no collisions, final SLAM error <= 3 cm), and says whether it passes.
# It prints the surface the map holds (summary.json surface_coverage: the share of the surface visible
# from the reachable floor that lies within 3 cm of a map point) and the modelled mission time split
# into scanning, driving and compute, and the mesh's distance to the world's true surfaces (median, RMS,
# 95th percentile) with the share of the visible surface it covers within 3 cm (unless mesh:=false).
# Next to every run's scans it prints the known-map reference of its world (coverage_oracle,
# scanstop_eval: the fewest perfect scans that see 99 % of the reachable floor, from the same start)
# and the ratio scans / reference; the reference is computed once per world and start and kept in
# the bench directory (oracle/<world>.json; office_large with a 1 m candidate grid).
#
#   bash scripts/bench_explore.sh [world[+arg:=value...] ...]      (build first: bash scripts/build.sh)
#   e.g. bash scripts/bench_explore.sh room_10x8+min_scan_travel:=2.0+seed:=2
# Environment: SCANSTOP_BENCH_DIR (default runs/bench-<date>-<time>), SCANSTOP_BENCH_ARGS (extra
# roslaunch arguments, e.g. "planes:=100 mesh:=false"), SCANSTOP_BENCH_ORACLE (0: no reference).
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
if [[ ${#worlds[@]} -eq 0 ]]; then
  worlds=(room_10x8 room_10x8+min_scan_travel:=2.0 office_loop corridor turtlebot3_house furnished_1 furnished_2
          furnished_3 office_large)
fi
out="${SCANSTOP_BENCH_DIR:-$root/runs/bench-$(date +%Y%m%d-%H%M%S)}"
mkdir -p "$out"
export ROS_IP=127.0.0.1
unset ROS_HOSTNAME  # it would take precedence over ROS_IP: keep every node on loopback
mkdir -p "$out/oracle"
# The known-map reference of a world from a start ("" = the documented one), computed once: prints its
# file (oracle/<world>[@<start>].json), or nothing when the oracle failed (named on stderr).
reference() {
  local world="$1" file="$2" start="$3" key="$1" args=()
  if [[ -n "$start" ]]; then key="$world@${start//,/_}"; args+=(--start "$start"); fi
  if [[ "$world" == office_large ]]; then args+=(--grid 1.0); fi  # 50 x 40 m: about 2,000 candidates at 1 m
  local json="$out/oracle/$key.json"
  if [[ ! -s "$json" ]]; then
    if ! nice "$root/devel/lib/scanstop_eval/coverage_oracle" "$file" --json --quiet ${args[@]+"${args[@]}"} \
        > "$json.tmp" 2> "$out/oracle/$key.log"; then
      echo "bench_explore: coverage_oracle $world failed: $(tail -1 "$out/oracle/$key.log")" >&2
      rm -f "$json.tmp"
      return 0
    fi
    mv "$json.tmp" "$json"
  fi
  echo "$json"
}
for entry in "${worlds[@]}"; do
  w="${entry%%+*}"
  extra=()
  if [[ "$entry" == *+* ]]; then IFS='+' read -r -a extra <<< "${entry#*+}"; fi
  name="${entry//:=/=}"
  file="$root/worlds/$w.stl"
  if [[ "$w" == turtlebot3_house ]]; then file="$root/../shared/data/worlds/turtlebot3_house.stl"; fi
  port=$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
  echo "bench_explore: $entry -> $out/$name"
  # shellcheck disable=SC2086
  ROS_MASTER_URI="http://127.0.0.1:$port" ROS_LOG_DIR="$out/$name/ros_log" roslaunch -p "$port" \
    "$root/launch/sim_explore.launch" world:="$w" world_file:="$file" run_dir:="$out/$name" planes:=400 \
    ${extra[@]+"${extra[@]}"} ${SCANSTOP_BENCH_ARGS:-} > "$out/$name.log" 2>&1 || echo "bench_explore: $entry: roslaunch exit $?" >&2
  if [[ "${SCANSTOP_BENCH_ORACLE:-1}" != 0 ]]; then
    start=""
    for a in ${extra[@]+"${extra[@]}"}; do [[ "$a" == start_pose:=* ]] && start="${a#start_pose:=}"; done
    ref_json="$(reference "$w" "$file" "$start")"
    [[ -n "$ref_json" ]] && echo "$ref_json" > "$out/$name.oracle"
    /usr/bin/python3 - "$out/$name/summary.json" "$ref_json" "$entry" <<'PY' || true
import json, os, sys
summary, ref, entry = sys.argv[1:4]
scans = json.load(open(summary))["scans"] if os.path.exists(summary) else None
r = json.load(open(ref))["floor"]["scans"]["99"] if ref else None
print("bench_explore: %s: %s scans, reference %s (coverage_oracle: scans for 99 %% of the reachable floor), ratio %s" % (
    entry, "-" if scans is None else scans, "-" if r is None else r,
    "%.1f" % (scans / r) if scans is not None and r else "-"))
PY
  fi
done
/usr/bin/python3 - "$out" "${worlds[@]}" <<'PY'
import json, os, sys
out, entries = sys.argv[1], sys.argv[2:]
print("\n| run | state | scans | reference (99 % floor) | scans / reference | coverage (true) | surface held (true) | modelled time: scanning + driving + compute | collisions | min clearance (legs < 5 cm) | ATE RMS / max (scan) | final SLAM error | odometry ATE RMS / final | compute/cycle mean (max) | scan time | mission wall time | mesh: triangles, median / RMS / p95, covered |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
verdicts = []
for e in entries:
    name = e.replace(":=", "=")
    p = os.path.join(out, name, "summary.json")
    if not os.path.exists(p):
        print("| %s | no summary (see %s/%s.log) |" % (e, out, name)); continue
    s = json.load(open(p))
    ref = None
    link = os.path.join(out, name + ".oracle")
    if os.path.exists(link):
        ref = json.load(open(open(link).read().strip()))["floor"]["scans"]["99"]
    ratio = "%.1f" % (s["scans"] / ref) if ref else "-"
    err = lambda k: ("%.1f cm" % (100 * s[k])) if s.get(k) is not None else "-"
    true_cov = s.get("true_coverage")
    ate = "-" if s.get("ate_rms_m") is None else "%s / %s (%d)" % (err("ate_rms_m"), err("ate_max_m"), s["ate_max_scan"])
    clear = "-" if s.get("min_clearance_m") is None else "%s (%d of %d)" % (
        err("min_clearance_m"), s["legs_closer_than_5cm"], s["legs_measured"])
    surface = "-" if s.get("surface_coverage") is None else "%.1f %%" % (100 * s["surface_coverage"])
    mesh = "-" if s.get("mesh_distance_median_m") is None else "%.2f M, %.1f / %.1f / %.1f mm, %.1f %%" % (
        s["mesh_triangles"] / 1e6, 1e3 * s["mesh_distance_median_m"], 1e3 * s["mesh_distance_rms_m"],
        1e3 * s["mesh_distance_p95_m"], 100 * s["mesh_surface_coverage"])
    minutes = lambda k: "-" if s.get(k) is None else "%.1f" % (s[k] / 60.0)
    time_split = "%s min: %s + %s + %s" % (minutes("modelled_time_s"), minutes("modelled_scanning_s"),
                                            minutes("modelled_driving_s"), minutes("modelled_compute_s"))
    print("| %s | %s | %d | %s | %s | %.1f %% (%s) | %s | %s | %d | %s | %s | %s | %s / %s | %.2f s (%.2f s) | %.0f s | %.0f s | %s |" % (
        e, s["state"], s["scans"], "-" if ref is None else ref, ratio, 100 * s["coverage"], "-" if true_cov is None else "%.1f %%" % (100 * true_cov),
        surface, time_split, s["collisions"], clear, ate, err("final_slam_error_m"), err("odometry_ate_rms_m"), err("final_odometry_error_m"),
        s["compute_per_cycle_mean_s"], s["compute_per_cycle_max_s"], s["scan_time_mean_s"], s["elapsed_s"], mesh))
    if e == "room_10x8+min_scan_travel:=2.0":
        checks = [("DONE", s["state"] == "DONE"), ("<= 21 scans", s["scans"] <= 21),
                  (">= 95 % of the reachable floor", (true_cov or 0.0) >= 0.95), ("no collisions", s["collisions"] == 0),
                  ("final SLAM error <= 3 cm", (s.get("final_slam_error_m") or 1e9) <= 0.03)]
        failed = [c for c, ok in checks if not ok]
        verdicts.append("acceptance run %s: %s" % (e, "PASS" if not failed else "FAIL (" + ", ".join(failed) + ")"))
for v in verdicts:
    print(v)
PY
