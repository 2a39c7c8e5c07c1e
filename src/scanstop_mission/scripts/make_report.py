#!/usr/bin/env python3
"""The run report's plots and one-page report.html, from what a run directory holds.

    make_report.py RUN_DIR [--out DIR]

Works on any run directory, live or finished, simulated or on the robot. It reads
  map/poses.csv            the scan poses (SLAM and odometry, stamps): required
  mission_state.yaml       per-scan coverage, true poses (simulation), scan times: optional
  summary.json             the final figures, true coverage (simulation): optional
  explorer/floor_map.yaml  the explorer's latest floor grid, georeferenced (map_server format): optional
  explorer/step_NNN_plan.json  the explorer's coverage per plan (when mission_state.yaml is missing)
and writes, beside report.md (into --out, default RUN_DIR):
  report_coverage.png, report_trajectory.png, report_pose_error.png (only with true poses), report.html.
What is missing is left out of the plots with a note on the page. Every input is read before anything
is written: a bad input ends the script with exit status 1 and a message naming the file (and line),
and nothing in RUN_DIR is changed or deleted. Files are written atomically (temporary file, rename).
"""
import argparse
import csv
import glob
import html
import json
import math
import os
import sys
import tempfile

POSES_FIELDS = ["index", "file", "stamp_s", "map_x", "map_y", "map_yaw", "odom_x", "odom_y", "odom_yaw"]


class InputError(Exception):
    """A run directory file that cannot be read: the message names it."""


def read_poses(path):
    """map/poses.csv: a list of dicts (index, stamp_s, map (x, y, yaw), odom (x, y, yaw))."""
    if not os.path.isfile(path):
        raise InputError("%s: missing (the scan poses; is this a run directory?)" % path)
    rows = []
    with open(path, newline="") as f:
        reader = csv.reader(f)
        header = next(reader, None)
        if header is None or header[:len(POSES_FIELDS)] != POSES_FIELDS:
            raise InputError("%s line 1: expected a header starting %s, got %s" %
                             (path, ",".join(POSES_FIELDS), ",".join(header or [])))
        for line_no, fields in enumerate(reader, start=2):
            if not fields:
                continue
            if len(fields) != len(header):
                raise InputError("%s line %d: %d fields, the header has %d" % (path, line_no, len(fields), len(header)))
            rec = dict(zip(header, fields))
            try:
                index = int(rec["index"])
                num = {k: float(rec[k]) for k in POSES_FIELDS if k not in ("index", "file")}
            except ValueError as e:
                raise InputError("%s line %d: not a number (%s)" % (path, line_no, e))
            if not all(math.isfinite(v) for v in num.values()):
                raise InputError("%s line %d: a value is not finite" % (path, line_no))
            rows.append({"index": index, "stamp_s": num["stamp_s"],
                         "map": (num["map_x"], num["map_y"], num["map_yaw"]),
                         "odom": (num["odom_x"], num["odom_y"], num["odom_yaw"])})
    return rows


def read_yaml(path):
    import yaml
    try:
        with open(path) as f:
            data = yaml.safe_load(f)
    except yaml.YAMLError as e:
        raise InputError("%s: not YAML (%s)" % (path, str(e).replace("\n", " ")))
    if not isinstance(data, dict):
        raise InputError("%s: not a YAML mapping" % path)
    return data


def read_json(path):
    try:
        with open(path) as f:
            data = json.load(f)
    except ValueError as e:
        raise InputError("%s: not JSON (%s)" % (path, e))
    if not isinstance(data, dict):
        raise InputError("%s: not a JSON object" % path)
    return data


def pose3(value, path, what):
    if value is None:
        return None
    try:
        p = tuple(float(v) for v in value)
    except (TypeError, ValueError):
        raise InputError("%s: %s is not a pose [x, y, yaw]" % (path, what))
    if len(p) != 3:
        raise InputError("%s: %s is not a pose [x, y, yaw]" % (path, what))
    return p


def read_state(path):
    """mission_state.yaml: {index: {coverage, true_pose, scan_time_s, mission_time_s}}, the top-level mapping."""
    data = read_yaml(path)
    scans = {}
    for i, s in enumerate(data.get("scans") or []):
        if not isinstance(s, dict) or "index" not in s:
            raise InputError("%s: scans[%d] has no index" % (path, i))
        try:
            scans[int(s["index"])] = {
                "coverage": float(s["coverage"]) if s.get("coverage") is not None else None,
                "true_pose": pose3(s.get("true_pose"), path, "scans[%d].true_pose" % i),
                "scan_time_s": float(s.get("scan_time_s") or 0.0),
                "mission_time_s": float(s["mission_time_s"]) if s.get("mission_time_s") is not None else None}
        except (TypeError, ValueError):
            raise InputError("%s: scans[%d] has a field that is not a number" % (path, i))
    return data, scans


def read_floor_map(path):
    """explorer/floor_map.yaml and its image: (grey image array, extent [x0, x1, y0, y1])."""
    import matplotlib.image as mpimg
    data = read_yaml(path)
    try:
        image = os.path.join(os.path.dirname(path), str(data["image"]))
        res = float(data["resolution"])
        ox, oy = float(data["origin"][0]), float(data["origin"][1])
    except (KeyError, TypeError, ValueError, IndexError):
        raise InputError("%s: needs image, resolution and origin [x, y, yaw]" % path)
    if not res > 0:
        raise InputError("%s: resolution %g is not positive" % (path, res))
    try:
        img = mpimg.imread(image)
    except (OSError, ValueError, SyntaxError) as e:
        raise InputError("%s: cannot read the image (%s)" % (image, e))
    if img.ndim == 3:
        img = img[..., 0]
    rows, cols = img.shape[:2]
    return img, [ox, ox + cols * res, oy, oy + rows * res], res


def explorer_coverage(run_dir):
    """Coverage per plan from explorer/step_NNN_plan.json: [(step, coverage)]."""
    out = []
    for path in sorted(glob.glob(os.path.join(run_dir, "explorer", "step_*_plan.json"))):
        data = read_json(path)
        try:
            out.append((int(os.path.basename(path)[5:8]), float(data["coverage"])))
        except (KeyError, TypeError, ValueError):
            raise InputError("%s: no coverage" % path)
    return out


def yaw_diff_deg(a, b):
    return abs(math.degrees(math.atan2(math.sin(a - b), math.cos(a - b))))


class Run:
    """Everything read from a run directory (nothing written)."""

    def __init__(self, run_dir):
        self.dir = run_dir
        self.notes = []
        if not os.path.isdir(run_dir):
            raise InputError("%s: not a directory" % run_dir)
        self.poses = read_poses(os.path.join(run_dir, "map", "poses.csv"))
        state_path = os.path.join(run_dir, "mission_state.yaml")
        self.state, self.scan_state = ({}, {})
        if os.path.isfile(state_path):
            self.state, self.scan_state = read_state(state_path)
        else:
            self.notes.append("no mission_state.yaml: coverage from the explorer's plans, no true poses")
        summary_path = os.path.join(run_dir, "summary.json")
        self.summary = read_json(summary_path) if os.path.isfile(summary_path) else {}
        if not self.summary:
            self.notes.append("no summary.json: the mission has not ended (a live run) or wrote no report")
        floor_path = os.path.join(run_dir, "explorer", "floor_map.yaml")
        self.floor = read_floor_map(floor_path) if os.path.isfile(floor_path) else None
        if self.floor is None:
            self.notes.append("no explorer/floor_map.yaml (written by explorer_node at every plan): "
                              "the trajectory is drawn without the floor map")
        self.plan_coverage = explorer_coverage(run_dir) if not self.scan_state else []
        self.world = self.summary.get("world") or self.state.get("world") or ""

        # Per scan: index, time, SLAM, odometry, truth, coverage.
        self.index = [p["index"] for p in self.poses]
        self.slam = [p["map"] for p in self.poses]
        self.odom = [p["odom"] for p in self.poses]
        self.truth = [self.scan_state.get(i, {}).get("true_pose") for i in self.index]
        self.coverage = [self.scan_state.get(i, {}).get("coverage") for i in self.index]
        # Mission time of each scan's coverage: the mission's modelled time when it was known
        # (scanning, driving and compute; mission_state.yaml's mission_time_s), else the stamps counted
        # from the start of the first scan (modelled time in simulation, the clock on the robot).
        mission_times = [self.scan_state.get(i, {}).get("mission_time_s") for i in self.index]
        if mission_times and all(t is not None and t > 0.0 for t in mission_times):
            self.time_min = [t / 60.0 for t in mission_times]
        else:
            t0 = self.poses[0]["stamp_s"] - self.scan_state.get(self.index[0], {}).get("scan_time_s", 0.0) \
                if self.poses else 0.0
            self.time_min = [(p["stamp_s"] - t0) / 60.0 for p in self.poses]
        self.has_truth = any(t is not None for t in self.truth)
        if not self.has_truth:
            self.notes.append("no true poses (a run on the robot, or before the simulator's ground truth): "
                              "no ground-truth trajectory and no pose error plot")
        self.true_coverage = self.summary.get("true_coverage")
        if self.true_coverage is None:
            self.notes.append("no true coverage (summary.json has none: not simulated, or no world file)")


def atomic_savefig(fig, path):
    fd, tmp = tempfile.mkstemp(prefix=".tmp_", suffix=".png", dir=os.path.dirname(path) or ".")
    os.close(fd)
    try:
        fig.savefig(tmp, dpi=110)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def atomic_write(path, text):
    fd, tmp = tempfile.mkstemp(prefix=".tmp_", dir=os.path.dirname(path) or ".")
    try:
        with os.fdopen(fd, "w") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def plot_coverage(run, plt, path):
    from matplotlib.ticker import MaxNLocator
    fig, (ax_s, ax_t) = plt.subplots(1, 2, figsize=(10, 3.8), sharey=True)
    scans = [k + 1 for k in range(len(run.index))]
    cov = [c * 100.0 if c is not None else float("nan") for c in run.coverage]
    if any(c is not None for c in run.coverage):
        ax_s.plot(scans, cov, "o-", color="tab:blue", ms=3, label="explorer's coverage (its map)")
        ax_t.plot(run.time_min, cov, "o-", color="tab:blue", ms=3, label="explorer's coverage (its map)")
    elif run.plan_coverage:
        steps = [s for s, _ in run.plan_coverage]
        ax_s.plot(steps, [c * 100.0 for _, c in run.plan_coverage], "o-", color="tab:blue", ms=3,
                  label="explorer's coverage (per plan)")
        ax_s.set_xlabel("plans")
    if run.true_coverage is not None and scans:
        tc = float(run.true_coverage) * 100.0
        ax_s.plot([scans[-1]], [tc], "*", color="tab:green", ms=12, label="true coverage (world), at the end")
        ax_t.plot([run.time_min[-1]], [tc], "*", color="tab:green", ms=12, label="true coverage (world), at the end")
    surface = run.summary.get("surface_coverage")
    if surface is not None and scans:
        sc = float(surface) * 100.0
        ax_s.plot([scans[-1]], [sc], "D", color="tab:purple", ms=7, label="visible surface held (world), at the end")
        ax_t.plot([run.time_min[-1]], [sc], "D", color="tab:purple", ms=7,
                  label="visible surface held (world), at the end")
    for ax in (ax_s, ax_t):
        ax.set_ylim(0, 105)
        ax.grid(alpha=0.3)
        ax.legend(loc="lower right", fontsize=8)
    ax_s.set_ylabel("coverage [%] (of the reachable floor)")
    if not ax_s.get_xlabel():
        ax_s.set_xlabel("scans")
    ax_s.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax_t.set_xlabel("mission time [min] (modelled in simulation)")
    ax_s.set_title("Coverage against scans")
    ax_t.set_title("Coverage against mission time")
    fig.tight_layout()
    atomic_savefig(fig, path)
    plt.close(fig)


def plot_trajectory(run, plt, path):
    from mpl_toolkits.axes_grid1.anchored_artists import AnchoredSizeBar
    fig, ax = plt.subplots(figsize=(8, 7))
    xs, ys = [], []
    if run.floor is not None:
        img, extent, _ = run.floor
        ax.imshow(img, cmap="gray", vmin=0, vmax=1 if img.max() <= 1.0 else 255, extent=extent,
                  origin="upper", interpolation="nearest")
        xs += extent[:2]
        ys += extent[2:]

    def draw(poses, style, color, label, keep_in_view, heading=False, alpha=1.0):
        pts = [p for p in poses if p is not None]
        if not pts:
            return
        ax.plot([p[0] for p in pts], [p[1] for p in pts], style, color=color, ms=3.5, lw=1.0, label=label,
                alpha=alpha)
        if heading:  # the scan headings, short arrows
            ax.quiver([p[0] for p in pts], [p[1] for p in pts], [math.cos(p[2]) for p in pts],
                      [math.sin(p[2]) for p in pts], color=color, width=0.0025, scale=60, alpha=0.8)
        if keep_in_view:
            xs.extend(p[0] for p in pts)
            ys.extend(p[1] for p in pts)

    draw(run.odom, "s--", "tab:red", "odometry", run.floor is None, alpha=0.5)
    if run.has_truth:
        draw(run.truth, "^-", "tab:green", "ground truth", True)
    draw(run.slam, "o-", "tab:blue", "SLAM (arrows: heading)", True, heading=True)
    every = max(1, int(math.ceil(len(run.slam) / 60.0)))
    for k, (i, p) in enumerate(zip(run.index, run.slam)):
        if k % every == 0 or k == len(run.slam) - 1:
            ax.annotate(str(i), (p[0], p[1]), textcoords="offset points", xytext=(4, 4), fontsize=7, color="navy")
    if xs:
        pad = 0.5
        ax.set_xlim(min(xs) - pad, max(xs) + pad)
        ax.set_ylim(min(ys) - pad, max(ys) + pad)
    ax.set_aspect("equal")
    span = ax.get_xlim()[1] - ax.get_xlim()[0]
    bar = [b for b in (0.5, 1, 2, 5, 10, 20, 50) if b <= span / 4.0]
    bar_m = bar[-1] if bar else 0.1
    ax.add_artist(AnchoredSizeBar(ax.transData, bar_m, "%g m" % bar_m, "lower left", pad=0.5, sep=4,
                                  frameon=True, size_vertical=span / 300.0))
    ax.set_xlabel("x [m] (map frame)")
    ax.set_ylabel("y [m]")
    title = "Scan poses" + (" over the explorer's final floor map" if run.floor is not None else "")
    ax.set_title(title + (" (every %d-th numbered)" % every if every > 1 else " (numbered)"), fontsize=10)
    handles, labels = ax.get_legend_handles_labels()
    if run.floor is not None:
        from matplotlib.patches import Patch
        handles += [Patch(facecolor="white", edgecolor="k", label="floor"), Patch(facecolor="black", label="obstacle"),
                    Patch(facecolor=(0.8, 0.8, 0.8), edgecolor="k", label="unknown")]
    ax.legend(handles=handles, loc="upper right", fontsize=8, framealpha=0.9)
    fig.tight_layout()
    atomic_savefig(fig, path)
    plt.close(fig)


def pose_errors(run):
    """[(scan, SLAM cm, odometry cm, SLAM yaw deg, odometry yaw deg)] where a true pose exists."""
    out = []
    for i, s, o, t in zip(run.index, run.slam, run.odom, run.truth):
        if t is None:
            continue
        out.append((i, math.hypot(s[0] - t[0], s[1] - t[1]) * 100.0, math.hypot(o[0] - t[0], o[1] - t[1]) * 100.0,
                    yaw_diff_deg(s[2], t[2]), yaw_diff_deg(o[2], t[2])))
    return out


def plot_pose_error(run, plt, path):
    from matplotlib.ticker import MaxNLocator
    err = pose_errors(run)
    fig, (ax_p, ax_y) = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    idx = [e[0] for e in err]
    ax_p.plot(idx, [e[1] for e in err], "o-", color="tab:blue", ms=3, label="SLAM")
    ax_p.plot(idx, [e[2] for e in err], "s--", color="tab:red", ms=3, label="odometry alone")
    ax_y.plot(idx, [e[3] for e in err], "o-", color="tab:blue", ms=3, label="SLAM")
    ax_y.plot(idx, [e[4] for e in err], "s--", color="tab:red", ms=3, label="odometry alone")
    ax_p.set_yscale("symlog", linthresh=1.0)
    ax_y.set_yscale("symlog", linthresh=0.1)
    ax_p.set_ylabel("position error [cm]")
    ax_y.set_ylabel("yaw error [deg]")
    ax_y.set_xlabel("scan")
    ax_y.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax_p.set_title("Pose error per scan against ground truth (log scale above 1 cm / 0.1 deg)", fontsize=10)
    for ax in (ax_p, ax_y):
        ax.grid(alpha=0.3, which="both")
        ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    atomic_savefig(fig, path)
    plt.close(fig)


def fmt(v, scale=1.0, digits=1, unit=""):
    if v is None:
        return "-"
    try:
        return ("%." + str(digits) + "f%s") % (float(v) * scale, unit)
    except (TypeError, ValueError):
        return html.escape(str(v))


def write_html(run, out_dir, images):
    s = run.summary
    rows = [("world", html.escape(run.world or "-")),
            ("state", html.escape(str(s.get("state") or run.state.get("state") or "-"))),
            ("scans", str(len(run.index))),
            ("coverage (explorer's map)", fmt(s.get("coverage", run.state.get("coverage")), 100.0, 1, " %")),
            ("true coverage (world)", fmt(run.true_coverage, 100.0, 1, " %")),
            ("collisions", html.escape(str(s.get("collisions", run.state.get("collisions", "-"))))),
            ("modelled mission time", fmt(s.get("modelled_time_s", run.state.get("modelled_time_s")), 1 / 60.0, 1,
                                          " min"))]
    if s.get("modelled_scanning_s") is not None:
        rows.append(("... of it scanning / driving / compute", "%s / %s / %s" % (
            fmt(s.get("modelled_scanning_s"), 1 / 60.0, 1, " min"), fmt(s.get("modelled_driving_s"), 1 / 60.0, 1, " min"),
            fmt(s.get("modelled_compute_s"), 1 / 60.0, 1, " min"))))
    if s.get("surface_coverage") is not None:
        rows.insert(5, ("surface held by the map (world)", fmt(s.get("surface_coverage"), 100.0, 1, " %")))
    if s.get("mesh_distance_median_m") is not None:
        rows.append(("mesh against the world: median / RMS / p95; covered", "%s / %s / %s; %s (%s triangles)" % (
            fmt(s.get("mesh_distance_median_m"), 1000.0, 1, " mm"), fmt(s.get("mesh_distance_rms_m"), 1000.0, 1, " mm"),
            fmt(s.get("mesh_distance_p95_m"), 1000.0, 1, " mm"), fmt(s.get("mesh_surface_coverage"), 100.0, 1, " %"),
            html.escape(str(s.get("mesh_triangles"))))))
    err = pose_errors(run)
    if err:
        rms = math.sqrt(sum(e[1] ** 2 for e in err) / len(err))
        worst = max(err, key=lambda e: e[1])
        rows.append(("SLAM position error (%d scans)" % len(err),
                     "RMS %.1f cm, max %.1f cm (scan %d); yaw max %.2f deg" %
                     (rms, worst[1], worst[0], max(e[3] for e in err))))
    title = "Exploration report" + (": " + html.escape(run.world) if run.world else "")
    out = ["<!DOCTYPE html>", "<html><head><meta charset=\"utf-8\"><title>%s</title>" % title,
           "<style>body{font-family:sans-serif;max-width:1100px;margin:auto}"
           "td,th{border:1px solid #ccc;padding:2px 8px}table{border-collapse:collapse}"
           "img{max-width:100%}</style></head><body>", "<h1>%s</h1>" % title, "<table>"]
    out += ["<tr><th>%s</th><td>%s</td></tr>" % (k, v) for k, v in rows]
    out.append("</table>")
    for caption, name in images:
        out.append("<h2>%s</h2><img src=\"%s\" alt=\"%s\">" % (caption, name, caption))
    if run.notes:
        out.append("<h2>Notes</h2><ul>" + "".join("<li>%s</li>" % html.escape(n) for n in run.notes) + "</ul>")
    out.append("<p>Details: <a href=\"report.md\">report.md</a>, summary.json, trajectory.csv, map/poses.csv; "
               "the explorer's step images in explorer/.</p></body></html>")
    atomic_write(os.path.join(out_dir, "report.html"), "\n".join(out) + "\n")


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("run_dir")
    ap.add_argument("--out", help="where to write (default: RUN_DIR)")
    args = ap.parse_args(argv)
    out_dir = args.out or args.run_dir
    try:
        run = Run(args.run_dir)
    except InputError as e:
        print("make_report.py: %s (nothing written)" % e, file=sys.stderr)
        return 1
    if not os.path.isdir(out_dir):
        print("make_report.py: %s: not a directory (nothing written)" % out_dir, file=sys.stderr)
        return 1
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    images = [("Coverage", "report_coverage.png"), ("Trajectory", "report_trajectory.png")]
    plot_coverage(run, plt, os.path.join(out_dir, images[0][1]))
    plot_trajectory(run, plt, os.path.join(out_dir, images[1][1]))
    if run.has_truth:
        images.append(("Pose error per scan", "report_pose_error.png"))
        plot_pose_error(run, plt, os.path.join(out_dir, images[2][1]))
    write_html(run, out_dir, images)
    print("make_report.py: wrote %s (%s)" % (os.path.join(out_dir, "report.html"), ", ".join(n for _, n in images)))
    for n in run.notes:
        print("make_report.py: note: %s" % n)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
