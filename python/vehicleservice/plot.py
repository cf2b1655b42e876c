"""vehicle-plot: a run at a glance, from the CSV of ``vehicle-sim --trace``
(columns: host_sim/trace.h) or ``vehiclectl record``.

Four panels: the path in the plane (commanded and measured, with the
waypoints given, else where the unit came to rest or a queued command
ended), the
translation and rotation speed, the commanded acceleration, and the
following error (commanded minus measured pose; vehicle-sim traces only),
each over time with the limits drawn in: the set velocity and acceleration
(--velocity/--acceleration, else the configuration's defaults), the hard
limits and the following-error threshold from --config. Headless
(matplotlib's Agg); the output's suffix picks PNG or SVG.

It prints what it drew, one "name value..." line each, so a script can check
a run against its limits.
"""
import argparse
import csv
import math
import sys
import xml.etree.ElementTree as ET


def read_config(path):
    """Limits, defaults and the following-error threshold of a vehicle.xml;
    the values of vs_config_defaults() where an attribute is missing."""
    cfg = {"limit_v": [1000.0, 180.0], "limit_a": [1000.0, 360.0],
           "set_v": [500.0, 90.0], "set_a": [500.0, 180.0], "follow_mm": 50.0}
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
    return cfg


def read_trace(path):
    """Columns as lists of floats (text columns dropped), and the kind:
    'sim' (vehicle-sim --trace) or 'record' (vehiclectl record)."""
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
    if "cmd_x_mm" in cols:
        kind = "sim"
    elif "x_mm" in cols and "t_s" in cols:
        kind = "record"
    else:
        raise ValueError("%s: neither a vehicle-sim trace nor a vehiclectl record" % path)
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


def analyse(cols, kind):
    """The series the panels draw, and the waypoints."""
    if kind == "sim":
        t = cols["time_s"]
        th = [math.radians(a) for a in cols["cmd_th_deg"]]
        # body velocity -> speed along the path (sideways speed included)
        vt = [math.hypot(a, b) for a, b in zip(cols["cmd_vx_mm_s"], cols["cmd_vy_mm_s"])]
        vr = cols["cmd_w_deg_s"]
        at = derivative(t, vt)
        ar = derivative(t, vr)
        err = [math.hypot(cx - ox, cy - oy) for cx, cy, ox, oy in
               zip(cols["cmd_x_mm"], cols["cmd_y_mm"], cols["odo_x_mm"], cols["odo_y_mm"])]
        path_cmd = (cols["cmd_x_mm"], cols["cmd_y_mm"])
        path_meas = (cols["odo_x_mm"], cols["odo_y_mm"])
        q = cols["queue_len"]
        marks = [0] + [i for i in range(1, len(t)) if q[i] < q[i - 1] or
                       (vt[i] == 0 and vr[i] == 0 and (vt[i - 1] != 0 or vr[i - 1] != 0))]
        del th
    else:
        t = cols["t_s"]
        vt = [abs(v) for v in cols["speed_mm_s"]]
        vr = cols["speed_deg_s"]
        at = derivative(t, vt)
        ar = derivative(t, vr)
        err = None
        path_cmd = None
        path_meas = (cols["x_mm"], cols["y_mm"])
        marks = [0] + [i for i in range(1, len(t)) if vt[i] == 0 and vr[i] == 0 and
                       (vt[i - 1] != 0 or vr[i - 1] != 0)]
    marks.append(len(t) - 1)
    src = path_cmd or path_meas
    waypoints = []
    for i in marks:
        p = (src[0][i], src[1][i])
        if not waypoints or p != waypoints[-1]:
            waypoints.append(p)
    return {"t": t, "vt": vt, "vr": vr, "at": at, "ar": ar, "err": err,
            "path_cmd": path_cmd, "path_meas": path_meas, "waypoints": waypoints}


def peak(values):
    return max((abs(v) for v in values), default=0.0)


def plot(trace, outputs, cfg, title=None, out=sys.stdout, waypoints=None):
    import matplotlib

    matplotlib.use("Agg")
    # Text as text and no dates or random ids: small, reproducible SVG.
    matplotlib.rcParams["svg.fonttype"] = "none"
    matplotlib.rcParams["svg.hashsalt"] = "vehicle-plot"
    import matplotlib.pyplot as plt

    cols, kind = read_trace(trace)
    a = analyse(cols, kind)
    if waypoints:
        a["waypoints"] = [tuple(w) for w in waypoints]
    t = a["t"]
    fig, ax = plt.subplots(2, 2, figsize=(10, 7.5))
    fig.suptitle(title or trace)

    p = ax[0][0]
    if a["path_cmd"]:
        p.plot(*a["path_cmd"], "-", color="tab:blue", lw=1.2, label="commanded")
    p.plot(*a["path_meas"], "--", color="tab:orange", lw=1.0, label="measured")
    wx, wy = zip(*a["waypoints"])
    p.plot(wx, wy, "o", color="black", ms=4, label="waypoints")
    p.set_aspect("equal", adjustable="datalim")
    p.set_xlabel("x (mm)")
    p.set_ylabel("y (mm)")
    p.set_title("path")
    p.legend(fontsize=8)

    def limits(axis, set_value, hard, unit):
        for sign in (1, -1) if set_value is not None else ():
            axis.axhline(sign * set_value, color="tab:red", ls="--", lw=0.8,
                         label="set %g %s" % (set_value, unit) if sign > 0 else None)
        for sign in (1, -1) if hard is not None else ():
            axis.axhline(sign * hard, color="gray", ls=":", lw=0.8,
                         label="limit %g %s" % (hard, unit) if sign > 0 else None)

    v = ax[0][1]
    v.plot(t, a["vt"], color="tab:blue", lw=1.0, label="translation (mm/s)")
    v.plot(t, a["vr"], color="tab:green", lw=1.0, label="rotation (deg/s)")
    limits(v, cfg["set_v"][0], cfg["limit_v"][0], "mm/s")
    v.axhline(cfg["set_v"][1], color="tab:olive", ls="--", lw=0.8,
              label="set %g deg/s" % cfg["set_v"][1])
    v.axhline(-cfg["set_v"][1], color="tab:olive", ls="--", lw=0.8)
    v.set_title("velocity")
    v.set_xlabel("t (s)")
    v.legend(fontsize=7)

    c = ax[1][0]
    c.plot(t, a["at"], color="tab:blue", lw=1.0, label="translation (mm/s²)")
    c.plot(t, a["ar"], color="tab:green", lw=1.0, label="rotation (deg/s²)")
    limits(c, cfg["set_a"][0], cfg["limit_a"][0], "mm/s²")
    c.axhline(cfg["set_a"][1], color="tab:olive", ls="--", lw=0.8,
              label="set %g deg/s²" % cfg["set_a"][1])
    c.axhline(-cfg["set_a"][1], color="tab:olive", ls="--", lw=0.8)
    c.set_title("acceleration")
    c.set_xlabel("t (s)")
    c.legend(fontsize=7)

    e = ax[1][1]
    if a["err"] is not None:
        e.plot(t, a["err"], color="tab:purple", lw=1.0, label="|commanded - measured| (mm)")
        e.axhline(cfg["follow_mm"], color="gray", ls=":", lw=0.8,
                  label="fault at %g mm" % cfg["follow_mm"])
        e.set_yscale("symlog", linthresh=0.01)
        e.legend(fontsize=7)
    else:
        e.text(0.5, 0.5, "no commanded pose in a vehiclectl record", ha="center",
               va="center", transform=e.transAxes)
    e.set_title("following error")
    e.set_xlabel("t (s)")
    fig.tight_layout()
    for o in outputs:
        meta = {"Date": None} if o.lower().endswith(".svg") else {}
        fig.savefig(o, dpi=80, metadata=meta)
    plt.close(fig)

    print("set_velocity %g %g" % tuple(cfg["set_v"]), file=out)
    print("set_acceleration %g %g" % tuple(cfg["set_a"]), file=out)
    print("velocity_limit %g %g" % tuple(cfg["limit_v"]), file=out)
    print("acceleration_limit %g %g" % tuple(cfg["limit_a"]), file=out)
    print("following_error_limit %g" % cfg["follow_mm"], file=out)
    print("peak_velocity %.3f %.3f" % (peak(a["vt"]), peak(a["vr"])), file=out)
    print("peak_acceleration %.3f %.3f" % (peak(a["at"]), peak(a["ar"])), file=out)
    if a["err"] is not None:
        print("peak_following_error %.4f" % peak(a["err"]), file=out)
    print("waypoints %d" % len(a["waypoints"]), file=out)
    print("samples %d duration %.3f" % (len(t), t[-1] - t[0] if t else 0.0), file=out)
    return a


def main(argv=None):
    ap = argparse.ArgumentParser(prog="vehicle-plot", description=__doc__.split("\n\n")[0])
    ap.add_argument("trace", help="CSV of vehicle-sim --trace or vehiclectl record")
    ap.add_argument("-o", "--output", action="append", required=True,
                    help="figure file, .png or .svg (repeatable)")
    ap.add_argument("--config", help="vehicle.xml: limits, defaults, following error")
    ap.add_argument("--velocity", nargs=2, type=float, metavar=("MM_S", "DEG_S"),
                    help="the set velocity of the run (setVelocity)")
    ap.add_argument("--acceleration", nargs=2, type=float, metavar=("MM_S2", "DEG_S2"),
                    help="the set acceleration of the run (setAcceleration)")
    ap.add_argument("--waypoint", nargs=2, type=float, action="append", metavar=("X", "Y"),
                    help="a waypoint of the run (repeatable; default: where the unit "
                         "came to rest or a queued command ended)")
    ap.add_argument("--title")
    args = ap.parse_args(argv)
    for o in args.output:
        if not o.lower().endswith((".png", ".svg")):
            ap.error("%s: .png or .svg" % o)
    cfg = read_config(args.config)
    if args.velocity:
        cfg["set_v"] = list(args.velocity)
    if args.acceleration:
        cfg["set_a"] = list(args.acceleration)
    try:
        plot(args.trace, args.output, cfg, args.title, waypoints=args.waypoint)
    except (OSError, ValueError, ET.ParseError) as e:
        print("vehicle-plot: %s" % e, file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
