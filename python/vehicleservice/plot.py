"""vehicle-plot: a run at a glance, from the CSV of ``vehicle-sim --trace``,
``vehiclectl record`` or a black box (``vehiclectl bbox``, ``--bbox-file``;
columns: docs/trace.md).

What an engineer tuning a base looks for, one quantity and one unit per
axis: the path in the plane (commanded and measured, with the waypoints
given, else where the unit came to rest or a queued command ended); heading
over time; translation and rotation velocity, and translation and rotation
acceleration, each commanded and measured, with the set value (--velocity,
--acceleration, else the configuration's defaults) and the hard limit of
--config drawn as dashed lines; the wheels' setpoints and measured speeds at
the rim; the following error (position and heading, commanded minus
measured, with the fault threshold); and a strip of the unit's state and
its newest alarm over time; a black box's fault as a vertical line with its
code on every panel over time (its wheels measured from the encoders).
Measured velocity is the odometry's change over
a window of WINDOW_S (the encoders' counts make a tick's change noisy).
Headless (matplotlib's Agg); the output's suffix picks PNG or SVG.

It prints the limits and the run's peaks, one "name value..." line each, so
a script can check a run against its limits; --describe adds what each
panel drew (title, axis labels, lines and their style).
"""
import argparse
import csv
import math
import sys
import xml.etree.ElementTree as ET

WINDOW_S = 0.02
STATES = {16: "Ready", 17: "Busy", 18: "Warning", 19: "Alarm", 20: "Stuck", 21: "Paused",
          22: "Avoid", 23: "Locked", 24: "Powered", 25: "Unpowered"}
STATE_COLOURS = {16: "tab:green", 17: "tab:blue", 18: "tab:orange", 19: "tab:red",
                 20: "tab:brown", 21: "gold", 22: "tab:pink", 23: "tab:purple",
                 24: "silver", 25: "gray"}
LINESTYLES = {"-": "solid", "--": "dashed", ":": "dotted", "-.": "dashdot", "None": "markers"}


def read_config(path):
    """Limits, defaults, the following-error threshold and the wheel geometry
    of a vehicle.xml; the values of vs_config_defaults() where an attribute is
    missing."""
    cfg = {"limit_v": [1000.0, 180.0], "limit_a": [1000.0, 360.0],
           "set_v": [500.0, 90.0], "set_a": [500.0, 180.0], "follow_mm": 50.0,
           "wheel_mm": 150.0, "counts_per_rev": 16384.0}
    if not path:
        return cfg
    root = ET.parse(path).getroot()
    for tag, vkey, akey in (("limits", "limit_v", "limit_a"), ("defaults", "set_v", "set_a")):
        e = root.find(tag)
        if e is None:
            continue
        for i, name in enumerate(("vel_t_mm_s", "vel_r_deg_s")):
            if name in e.attrib:
                cfg[vkey][i] = float(e.attrib[name])
        for i, name in enumerate(("acc_t_mm_s2", "acc_r_deg_s2")):
            if name in e.attrib:
                cfg[akey][i] = float(e.attrib[name])
    e = root.find("supervision")
    if e is not None and "following_error_mm" in e.attrib:
        cfg["follow_mm"] = float(e.attrib["following_error_mm"])
    e = root.find("geometry")
    if e is not None:
        cfg["wheel_mm"] = float(e.attrib.get("wheel_diameter_mm", cfg["wheel_mm"]))
        cfg["counts_per_rev"] = float(e.attrib.get("encoder_counts_per_rev",
                                                   cfg["counts_per_rev"]))
    return cfg


def read_trace(path):
    """Columns as lists of floats (text columns dropped), and the kind:
    'sim' (vehicle-sim --trace), 'stream' (vehiclectl record over frames:
    the unit's telemetry stream) or 'record' (vehiclectl record polling)."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if not rows:
        raise ValueError("%s: empty" % path)
    head = rows[0]
    cols = {name: [] for name in head}
    for r in rows[1:]:
        for name, v in zip(head, r):
            cols[name].append(v)
    for name in list(cols):
        try:
            cols[name] = [float(v) for v in cols[name]]
        except ValueError:
            del cols[name]
    if "cmd_x_mm" in cols and "fault" in cols and "enc0" in cols:
        kind = "bbox"
    elif "cmd_x_mm" in cols:
        kind = "sim"
    elif "tick" in cols and "meas_vx_mm_s" in cols and "x_mm" in cols:
        kind = "stream"
    elif "x_mm" in cols and "t_s" in cols:
        kind = "record"
    else:
        raise ValueError("%s: neither a vehicle-sim trace nor a vehiclectl record" % path)
    if not cols.get("time_s" if kind in ("sim", "bbox") else "t_s"):
        raise ValueError("%s: no rows" % path)
    return cols, kind


def derivative(t, v):
    """Finite differences, one value per interval's end (the first repeats)."""
    out = [0.0]
    for i in range(1, len(t)):
        dt = t[i] - t[i - 1]
        out.append((v[i] - v[i - 1]) / dt if dt > 0 else out[-1])
    if len(out) > 1:
        out[0] = out[1]
    return out


def window(t, span):
    """Half-width in rows of a centred window at least span long."""
    if len(t) < 2:
        return 1
    steps = sorted(b - a for a, b in zip(t, t[1:]))
    dt = steps[len(steps) // 2]
    return max(1, int(math.ceil(span / 2 / dt - 1e-9))) if dt > 0 else 1


def rate(t, k, change):
    """change(i, j) / (t[j] - t[i]) over the centred window of half-width k
    (narrower at the ends)."""
    out = []
    n = len(t)
    for i in range(n):
        a, b = max(0, i - k), min(n - 1, i + k)
        out.append(change(a, b) / (t[b] - t[a]) if t[b] > t[a] else 0.0)
    return out


def unwrap(deg):
    """Headings without the jumps at +-180."""
    out = []
    for d in deg:
        if out:
            d = out[-1] + (d - out[-1] + 180.0) % 360.0 - 180.0
        out.append(d)
    return out


def segments(t, values):
    """(value, start, end) runs: each ends where the next starts, the last at
    the last sample."""
    runs = []
    for i, v in enumerate(values):
        if not runs or runs[-1][0] != v:
            if runs:
                runs[-1][2] = t[i]
            runs.append([v, t[i], t[i]])
    if runs:
        runs[-1][2] = t[-1]
    return [tuple(r) for r in runs]


def analyse(cols, kind, cfg):
    """The series the panels draw, and the waypoints."""
    fault = None
    if kind == "bbox":
        # the unit's own measurement: its encoders' counts over time
        for axis in range(4):
            cols["meas%d_cps" % axis] = derivative(cols["time_s"], cols["enc%d" % axis])
        hit = [i for i, f in enumerate(cols["fault"]) if f]
        if hit:
            fault = (cols["time_s"][hit[0]], int(cols["fault"][hit[0]]))
        kind = "sim"
    if kind == "sim":
        t = cols["time_s"]
        # body velocity -> speed along the path (sideways speed included)
        vt = [math.hypot(a, b) for a, b in zip(cols["cmd_vx_mm_s"], cols["cmd_vy_mm_s"])]
        vr = cols["cmd_w_deg_s"]
        x, y = cols["odo_x_mm"], cols["odo_y_mm"]
        th_meas = unwrap(cols["odo_th_deg"])
        th_cmd = unwrap(cols["cmd_th_deg"])
        err = [math.hypot(cx - ox, cy - oy) for cx, cy, ox, oy in
               zip(cols["cmd_x_mm"], cols["cmd_y_mm"], x, y)]
        err_th = [(c - m + 180.0) % 360.0 - 180.0 for c, m in
                  zip(cols["cmd_th_deg"], cols["odo_th_deg"])]
        path_cmd = (cols["cmd_x_mm"], cols["cmd_y_mm"])
        k = window(t, WINDOW_S)
        vt_meas = rate(t, k, lambda a, b: math.hypot(x[b] - x[a], y[b] - y[a]))
        vr_meas = rate(t, k, lambda a, b: th_meas[b] - th_meas[a])
        mm_per_count = cfg["wheel_mm"] * math.pi / cfg["counts_per_rev"]
        wheels = []
        for axis in range(4):
            sp, meas = cols.get("sp%d_cps" % axis), cols.get("meas%d_cps" % axis)
            if sp is None or meas is None or (axis >= 2 and not any(sp) and not any(meas)):
                continue
            wheels.append((axis, [v * mm_per_count for v in sp],
                           [v * mm_per_count for v in meas]))
        q = cols["queue_len"]
        marks = [0] + [i for i in range(1, len(t)) if q[i] < q[i - 1] or
                       (vt[i] == 0 and vr[i] == 0 and (vt[i - 1] != 0 or vr[i - 1] != 0))]
    elif kind == "stream":
        # the unit's own samples: commanded and measured body velocity
        t = cols["t_s"]
        th_cmd, err, err_th, path_cmd, wheels = None, None, None, None, None
        vt = [math.hypot(a, b) for a, b in zip(cols["cmd_vx_mm_s"], cols["cmd_vy_mm_s"])]
        vr = cols["cmd_w_deg_s"]
        x, y = cols["x_mm"], cols["y_mm"]
        th_meas = unwrap(cols["theta_deg"])
        vt_meas = [math.hypot(a, b) for a, b in zip(cols["meas_vx_mm_s"], cols["meas_vy_mm_s"])]
        vr_meas = cols["meas_w_deg_s"]
        k = window(t, WINDOW_S)
        q = cols["queue_len"]
        marks = [0] + [i for i in range(1, len(t)) if q[i] < q[i - 1]]
    else:
        t = cols["t_s"]
        vt, vr, th_cmd, err, err_th, path_cmd, wheels = None, None, None, None, None, None, None
        x, y = cols["x_mm"], cols["y_mm"]
        th_meas = unwrap(cols["theta_deg"])
        vt_meas = [abs(v) for v in cols["speed_mm_s"]]
        vr_meas = cols["speed_deg_s"]
        k = window(t, WINDOW_S)
        marks = [0] + [i for i in range(1, len(t)) if vt_meas[i] == 0 and vr_meas[i] == 0 and
                       (vt_meas[i - 1] != 0 or vr_meas[i - 1] != 0)]
    marks.append(len(t) - 1)
    path_meas = (x, y)
    src = path_cmd or path_meas
    waypoints = []
    for i in marks:
        p = (src[0][i], src[1][i])
        if not waypoints or p != waypoints[-1]:
            waypoints.append(p)
    state = cols.get("state")
    alarm = cols.get("newest_alarm")
    return {"t": t, "vt": vt, "vr": vr,
            "at": derivative(t, vt) if vt else None, "ar": derivative(t, vr) if vr else None,
            "vt_meas": vt_meas, "vr_meas": vr_meas,
            "at_meas": rate(t, k, lambda a, b: vt_meas[b] - vt_meas[a]),
            "ar_meas": rate(t, k, lambda a, b: vr_meas[b] - vr_meas[a]),
            "th_cmd": th_cmd, "th_meas": th_meas, "err": err, "err_th": err_th,
            "wheels": wheels, "path_cmd": path_cmd, "path_meas": path_meas, "fault": fault,
            "waypoints": waypoints,
            "states": segments(t, [int(s) for s in state]) if state else [],
            "alarms": segments(t, [int(a) for a in alarm]) if alarm else None}


def peak(values):
    return max((abs(v) for v in values), default=0.0)


def limit_lines(axis, set_value, hard, unit, both_signs):
    """The set value and the hard limit as dashed lines (+ and -, or + only
    for a speed, which has no sign)."""
    for value, colour, dashes, name in ((set_value, "tab:orange", (0, (6, 3)), "set"),
                                        (hard, "tab:red", (0, (3, 2)), "limit")):
        for sign in (1, -1) if both_signs else (1,):
            axis.axhline(sign * value, color=colour, ls=dashes, lw=0.9,
                         label="%s %s%g %s" % (name, "\u00b1" if both_signs else "", value, unit)
                         if sign > 0 else None)


def over_time(axis, t, cmd, meas, title, ylabel):
    # Measured thin over a wide pale commanded: both show where they agree.
    if cmd is not None:
        axis.plot(t, cmd, "-", color="tab:blue", lw=2.4, alpha=0.4, label="commanded")
    axis.plot(t, meas, "-", color="darkgreen", lw=0.8, label="measured")
    axis.set_title(title)
    axis.set_ylabel(ylabel)
    axis.set_xlabel("t (s)")


def note(axis, text):
    axis.text(0.5, 0.5, text, ha="center", va="center", transform=axis.transAxes)


def timeline(axis, a):
    """The state lane (y 1) and the newest-alarm lane (y 0)."""
    for code, start, end in a["states"]:
        axis.broken_barh([(start, end - start)], (0.6, 0.8),
                         color=STATE_COLOURS.get(code, "black"), label=STATES.get(code, str(code)))
    lanes = ["state"]
    if a["alarms"] is not None:
        lanes = ["alarm", "state"]
        for code, start, end in a["alarms"]:
            if code == 0:
                continue
            fault = code >= 200
            axis.broken_barh([(start, end - start)], (-0.4, 0.8),
                             color="tab:red" if fault else "tab:orange")
            axis.text(start, 0, " %s %d" % ("fault" if fault else "warning", code),
                      va="center", ha="left", fontsize=7)
    # One legend entry per state shown, in the order of first appearance.
    handles, labels = axis.get_legend_handles_labels()
    seen = {}
    for h, lab in zip(handles, labels):
        seen.setdefault(lab, h)
    axis.legend(seen.values(), seen.keys(), fontsize=7, ncol=min(len(seen), 6) or 1,
                loc="upper left", bbox_to_anchor=(0, -0.45))
    axis.set_yticks(range(2 - len(lanes), 2))
    axis.set_yticklabels(lanes)
    axis.set_ylim(-0.6 if len(lanes) == 2 else 0.4, 1.6)
    axis.set_title("state and alarms")
    axis.set_xlabel("t (s)")


def draw(fig, a, cfg):
    """The panels, in reading order; returns them with their twin axes."""
    g = fig.add_gridspec(5, 2, height_ratios=[3, 3, 3, 3, 1.1])
    path = fig.add_subplot(g[0, 0])
    head = fig.add_subplot(g[0, 1])
    vel_t = fig.add_subplot(g[1, 0], sharex=head)
    vel_r = fig.add_subplot(g[1, 1], sharex=head)
    acc_t = fig.add_subplot(g[2, 0], sharex=head)
    acc_r = fig.add_subplot(g[2, 1], sharex=head)
    wheel = fig.add_subplot(g[3, 0], sharex=head)
    follow = fig.add_subplot(g[3, 1], sharex=head)
    strip = fig.add_subplot(g[4, :], sharex=head)
    t = a["t"]

    if a["path_cmd"]:
        path.plot(*a["path_cmd"], "-", color="tab:blue", lw=2.4, alpha=0.4, label="commanded")
    path.plot(*a["path_meas"], "--", color="darkgreen", lw=0.9, label="measured")
    wx, wy = zip(*a["waypoints"])
    path.plot(wx, wy, "o", color="black", ms=4, label="waypoints")
    path.set_aspect("equal", adjustable="datalim")
    path.set_xlabel("x (mm)")
    path.set_ylabel("y (mm)")
    path.set_title("path")

    over_time(head, t, a["th_cmd"], a["th_meas"], "heading", "heading (deg)")
    over_time(vel_t, t, a["vt"], a["vt_meas"], "translation velocity", "speed (mm/s)")
    limit_lines(vel_t, cfg["set_v"][0], cfg["limit_v"][0], "mm/s", False)
    over_time(vel_r, t, a["vr"], a["vr_meas"], "rotation velocity", "rotation (deg/s)")
    limit_lines(vel_r, cfg["set_v"][1], cfg["limit_v"][1], "deg/s", True)
    over_time(acc_t, t, a["at"], a["at_meas"], "translation acceleration",
              "acceleration (mm/s\u00b2)")
    limit_lines(acc_t, cfg["set_a"][0], cfg["limit_a"][0], "mm/s\u00b2", True)
    over_time(acc_r, t, a["ar"], a["ar_meas"], "rotation acceleration",
              "acceleration (deg/s\u00b2)")
    limit_lines(acc_r, cfg["set_a"][1], cfg["limit_a"][1], "deg/s\u00b2", True)

    wheel.set_title("wheel speeds")
    wheel.set_ylabel("rim speed (mm/s)")
    wheel.set_xlabel("t (s)")
    if a["wheels"]:
        colours = ("tab:blue", "tab:green", "tab:purple", "tab:brown")
        for axis, sp, meas in a["wheels"]:
            wheel.plot(t, sp, "-", color=colours[axis], lw=1.0, label="axis %d setpoint" % axis)
            wheel.plot(t, meas, ":", color=colours[axis], lw=1.2, label="axis %d measured" % axis)
    else:
        note(wheel, "no wheel speeds in a vehiclectl record")

    follow.set_title("following error")
    follow.set_xlabel("t (s)")
    follow.set_ylabel("position error (mm)")
    twins = {}
    if a["err"] is not None:
        follow.plot(t, a["err"], "-", color="tab:purple", lw=1.0, label="position")
        follow.axhline(cfg["follow_mm"], color="tab:red", ls=(0, (3, 2)), lw=0.9,
                       label="fault at %g mm" % cfg["follow_mm"])
        follow.set_yscale("symlog", linthresh=0.01)
        th = follow.twinx()
        th.plot(t, a["err_th"], "-", color="tab:olive", lw=0.6, alpha=0.6, label="heading")
        th.set_ylabel("heading error (deg)")
        # The position error in front: the twin would cover it.
        follow.set_zorder(th.get_zorder() + 1)
        follow.patch.set_visible(False)
        twins[follow] = th
    else:
        note(follow, "no commanded pose in a vehiclectl record")

    timeline(strip, a)
    if a["fault"]:
        # the black box's trigger: where each panel over time stood then
        tf, code = a["fault"]
        for p in (head, vel_t, vel_r, acc_t, acc_r, wheel, follow, strip):
            p.axvline(tf, color="black", ls="-", lw=1.0,
                      label="fault %d" % code if p is not strip else None)
            if p is not strip:
                p.text(tf, 0.98, "fault %d " % code, transform=p.get_xaxis_transform(),
                       va="top", ha="right", fontsize=8)
    for p in (path, head, vel_t, vel_r, acc_t, acc_r, wheel):
        if p.get_legend_handles_labels()[0]:
            p.legend(fontsize=7)
    if follow in twins:
        h1, l1 = follow.get_legend_handles_labels()
        h2, l2 = twins[follow].get_legend_handles_labels()
        follow.legend(h1 + h2, l1 + l2, fontsize=7, loc="upper left")
    return [path, head, vel_t, vel_r, acc_t, acc_r, wheel, follow, strip], twins


def describe(panels, twins, out):
    """What each panel shows, from the axes themselves."""
    def lines(axis):
        for ln in axis.get_lines():
            if not ln.get_label().startswith("_"):
                print("  line %s: %s" % (ln.get_label(), LINESTYLES.get(ln.get_linestyle(),
                                                                        ln.get_linestyle())),
                      file=out)

    for p in panels:
        print("panel %s" % p.get_title(), file=out)
        print("  x: %s" % p.get_xlabel(), file=out)
        if p.get_ylabel():
            print("  y: %s" % p.get_ylabel(), file=out)
        else:
            print("  y lanes: %s" % ", ".join(t.get_text() for t in p.get_yticklabels()),
                  file=out)
        lines(p)
        if p in twins:
            print("  y right: %s" % twins[p].get_ylabel(), file=out)
            lines(twins[p])
        for txt in p.texts:
            if txt.get_transform() == p.transAxes:
                print("  note: %s" % txt.get_text(), file=out)
        if p.collections:
            legend = p.get_legend()
            print("  states: %s" % ", ".join(t.get_text() for t in legend.get_texts()),
                  file=out)
            print("  alarms: %s" % (", ".join(t.get_text().strip() for t in p.texts)
                                    or "none"), file=out)


def plot(trace, outputs, cfg, title=None, out=sys.stdout, waypoints=None, describe_to=None):
    import matplotlib

    matplotlib.use("Agg")
    # Text as text and no dates or random ids: small, reproducible SVG.
    matplotlib.rcParams["svg.fonttype"] = "none"
    matplotlib.rcParams["svg.hashsalt"] = "vehicle-plot"
    import matplotlib.pyplot as plt

    cols, kind = read_trace(trace)
    a = analyse(cols, kind, cfg)
    if waypoints:
        a["waypoints"] = [tuple(w) for w in waypoints]
    t = a["t"]
    fig = plt.figure(figsize=(12, 15))
    fig.suptitle(title or trace)
    panels, twins = draw(fig, a, cfg)
    fig.tight_layout(rect=(0, 0, 1, 0.985))
    for o in outputs:
        meta = {"Date": None} if o.lower().endswith(".svg") else {}
        fig.savefig(o, dpi=80, metadata=meta)

    print("set_velocity %g %g" % tuple(cfg["set_v"]), file=out)
    print("set_acceleration %g %g" % tuple(cfg["set_a"]), file=out)
    print("velocity_limit %g %g" % tuple(cfg["limit_v"]), file=out)
    print("acceleration_limit %g %g" % tuple(cfg["limit_a"]), file=out)
    print("following_error_limit %g" % cfg["follow_mm"], file=out)
    if a["vt"] is not None:
        print("peak_velocity %.3f %.3f" % (peak(a["vt"]), peak(a["vr"])), file=out)
        print("peak_acceleration %.3f %.3f" % (peak(a["at"]), peak(a["ar"])), file=out)
    print("peak_measured_velocity %.3f %.3f" % (peak(a["vt_meas"]), peak(a["vr_meas"])),
          file=out)
    if a["err"] is not None:
        print("peak_following_error %.4f" % peak(a["err"]), file=out)
        moving = [e for e, v, w in zip(a["err"], a["vt"], a["vr"]) if v != 0 or w != 0]
        if moving:
            print("following_error_moving %.4f %.4f" % (min(moving), max(moving)), file=out)
        print("peak_heading_error %.4f" % peak(a["err_th"]), file=out)
    print("waypoints %d" % len(a["waypoints"]), file=out)
    if a["states"]:
        code = a["states"][-1][0]
        print("final_state %d %s" % (code, STATES.get(code, "?")), file=out)
    if a["fault"]:
        print("fault %d at %.6f" % (a["fault"][1], a["fault"][0]), file=out)
    print("samples %d duration %.3f" % (len(t), t[-1] - t[0] if t else 0.0), file=out)
    if describe_to is not None:
        describe(panels, twins, describe_to)
    plt.close(fig)
    return a


def main(argv=None):
    ap = argparse.ArgumentParser(prog="vehicle-plot", description=__doc__.split("\n\n")[0])
    ap.add_argument("trace", help="CSV of vehicle-sim --trace, vehiclectl record or a black box")
    ap.add_argument("-o", "--output", action="append", default=[],
                    help="figure file, .png or .svg (repeatable)")
    ap.add_argument("--describe", action="store_true",
                    help="also print each panel: title, axis labels, lines and their style")
    ap.add_argument("--config", help="vehicle.xml: limits, defaults, following error, wheels")
    ap.add_argument("--velocity", nargs=2, type=float, metavar=("MM_S", "DEG_S"),
                    help="the set velocity of the run (setVelocity)")
    ap.add_argument("--acceleration", nargs=2, type=float, metavar=("MM_S2", "DEG_S2"),
                    help="the set acceleration of the run (setAcceleration)")
    ap.add_argument("--waypoint", nargs=2, type=float, action="append", metavar=("X", "Y"),
                    help="a waypoint of the run (repeatable; default: where the unit "
                         "came to rest or a queued command ended)")
    ap.add_argument("--title")
    args = ap.parse_args(argv)
    if not args.output and not args.describe:
        ap.error("-o FILE or --describe")
    for o in args.output:
        if not o.lower().endswith((".png", ".svg")):
            ap.error("%s: .png or .svg" % o)
    try:
        cfg = read_config(args.config)
        if args.velocity:
            cfg["set_v"] = list(args.velocity)
        if args.acceleration:
            cfg["set_a"] = list(args.acceleration)
        plot(args.trace, args.output, cfg, args.title, waypoints=args.waypoint,
             describe_to=sys.stdout if args.describe else None)
    except (OSError, ValueError, ET.ParseError) as e:
        print("vehicle-plot: %s" % e, file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
