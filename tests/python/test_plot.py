"""vehicle-plot renders a vehicle-sim trace: PNG and SVG files of a sane
size, the limits and peaks it prints are those of the configuration and
of the trace (computed here independently), and --describe names exactly the
panels, axis labels and lines it drew, for a trace and a vehiclectl record."""
import csv
import math
import os
import subprocess
import tempfile
import unittest

from simrig import BUILD, TOP


def polled(ms):
    """A host that waits ms while polling getState every 500 ms, as the link
    watchdog (1 s in config/vehicle.xml) expects of it."""
    return "$wait 500\ngetState\n" * (ms // 500)


SCRIPT = ("setPower true\nsetServo true\nsetVelocity 300 60\nmoveForward 600\n" + polled(4000) +
          "moveTurn 90\n" + polled(3000) + "moveCruiseAbs 600 400\n" + polled(4000))


def trace(tmp):
    path = os.path.join(tmp, "run.csv")
    subprocess.run([os.path.join(BUILD, "vehicle-sim"), "--fast", "--config",
                    os.path.join(TOP, "config/vehicle.xml"), "--io",
                    os.path.join(TOP, "config/io.xml"), "--trace", path, "--trace-every", "5"],
                   input=SCRIPT.encode(), check=True, capture_output=True, timeout=60)
    return path


def peaks(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    t = [float(r["time_s"]) for r in rows]
    vt = [math.hypot(float(r["cmd_vx_mm_s"]), float(r["cmd_vy_mm_s"])) for r in rows]
    vr = [float(r["cmd_w_deg_s"]) for r in rows]
    at = [(vt[i] - vt[i - 1]) / (t[i] - t[i - 1]) for i in range(1, len(t))]
    ar = [(vr[i] - vr[i - 1]) / (t[i] - t[i - 1]) for i in range(1, len(t))]
    err = [math.hypot(float(r["cmd_x_mm"]) - float(r["odo_x_mm"]),
                      float(r["cmd_y_mm"]) - float(r["odo_y_mm"])) for r in rows]
    m = lambda v: max(abs(x) for x in v)  # noqa: E731
    return m(vt), m(vr), m(at), m(ar), m(err), len(rows)


TIME_PANELS = """panel heading
  x: t (s)
  y: heading (deg)
{cmd}  line measured: solid
panel translation velocity
  x: t (s)
  y: speed (mm/s)
{cmd}  line measured: solid
  line set 500 mm/s: dashed
  line limit 1000 mm/s: dashed
panel rotation velocity
  x: t (s)
  y: rotation (deg/s)
{cmd}  line measured: solid
  line set \u00b190 deg/s: dashed
  line limit \u00b1180 deg/s: dashed
panel translation acceleration
  x: t (s)
  y: acceleration (mm/s\u00b2)
{cmd}  line measured: solid
  line set \u00b1500 mm/s\u00b2: dashed
  line limit \u00b11000 mm/s\u00b2: dashed
panel rotation acceleration
  x: t (s)
  y: acceleration (deg/s\u00b2)
{cmd}  line measured: solid
  line set \u00b1180 deg/s\u00b2: dashed
  line limit \u00b1360 deg/s\u00b2: dashed
panel wheel speeds
  x: t (s)
  y: rim speed (mm/s)
"""

DESCRIBE_SIM = ("""panel path
  x: x (mm)
  y: y (mm)
  line commanded: solid
  line measured: dashed
  line waypoints: markers
""" + TIME_PANELS.format(cmd="  line commanded: solid\n") + """  line axis 0 setpoint: solid
  line axis 0 measured: dotted
  line axis 1 setpoint: solid
  line axis 1 measured: dotted
panel following error
  x: t (s)
  y: position error (mm)
  line position: solid
  line fault at 50 mm: dashed
  y right: heading error (deg)
  line heading: solid
panel state and alarms
  x: t (s)
  y lanes: alarm, state
  states: Powered, Busy, Warning, Ready, Alarm
  alarms: warning 120, fault 208
""")

DESCRIBE_RECORD = ("""panel path
  x: x (mm)
  y: y (mm)
  line measured: dashed
  line waypoints: markers
""" + TIME_PANELS.format(cmd="") + """  note: no wheel speeds in a vehiclectl record
panel following error
  x: t (s)
  y: position error (mm)
  note: no commanded pose in a vehiclectl record
panel state and alarms
  x: t (s)
  y lanes: alarm, state
  states: Busy, Warning
  alarms: warning 153
""")


class Plot(unittest.TestCase):
    def test_renders_and_prints_the_limits(self):
        with tempfile.TemporaryDirectory() as tmp:
            csv_path = trace(tmp)
            png, svg = os.path.join(tmp, "run.png"), os.path.join(tmp, "run.svg")
            out = subprocess.run(
                ["/usr/bin/python3", os.path.join(TOP, "tools/vehicle-plot"), csv_path,
                 "-o", png, "-o", svg, "--config", os.path.join(TOP, "config/vehicle.xml"),
                 "--velocity", "300", "60"],
                capture_output=True, text=True, timeout=120)
            self.assertEqual(out.returncode, 0, out.stderr)
            got = dict(line.split(" ", 1) for line in out.stdout.splitlines())
            with open(png, "rb") as f:
                self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n")
            self.assertTrue(20000 < os.path.getsize(png) < 1000000, os.path.getsize(png))
            with open(svg) as f:
                text = f.read()
            self.assertIn("<svg", text)
            self.assertTrue(20000 < len(text) < 3000000, len(text))
            # what was drawn: the set velocity given, the rest from vehicle.xml
            self.assertEqual(got["set_velocity"], "300 60")
            self.assertEqual(got["set_acceleration"], "500 180")
            self.assertEqual(got["velocity_limit"], "1000 180")
            self.assertEqual(got["acceleration_limit"], "1000 360")
            self.assertEqual(got["following_error_limit"], "50")
            vt, vr, at, ar, err, n = peaks(csv_path)
            self.assertEqual(got["peak_velocity"], "%.3f %.3f" % (vt, vr))
            self.assertEqual(got["peak_acceleration"], "%.3f %.3f" % (at, ar))
            self.assertEqual(got["peak_following_error"], "%.4f" % err)
            self.assertEqual(got["samples"].split()[0], str(n))
            # and the trace keeps to them: 300 mm/s, 60 deg/s set; 500 mm/s^2
            self.assertEqual(got["peak_velocity"].split()[0], "300.000")
            self.assertLessEqual(vr, 60.0 + 1e-9)
            self.assertLessEqual(at, 500.0 + 1e-6)
            self.assertLessEqual(ar, 180.0 + 1e-6)
            self.assertLess(err, 50.0)

    def test_describe_names_every_panel_axis_and_line(self):
        """A short run through Powered, Busy, a refused move's warning, Ready
        and an emergency stop's fault: the PNG, and exactly what was drawn."""
        script = ("$watchdog 0\nsetPower true\n$wait 100\nsetServo true\nmoveForward 100\n"
                  "moveForward 50\n$wait 1200\nclearAlarm\n$wait 100\n$sim estop on\n"
                  "$wait 100\n")
        with tempfile.TemporaryDirectory() as tmp:
            csv_path = os.path.join(tmp, "short.csv")
            subprocess.run([os.path.join(BUILD, "vehicle-sim"), "--fast", "--trace", csv_path,
                            "--trace-every", "5"], input=script.encode(), check=True,
                           capture_output=True, timeout=60)
            png = os.path.join(tmp, "short.png")
            out = subprocess.run(
                ["/usr/bin/python3", os.path.join(TOP, "tools/vehicle-plot"), csv_path,
                 "-o", png, "--config", os.path.join(TOP, "config/vehicle.xml"), "--describe"],
                capture_output=True, text=True, timeout=120)
            self.assertEqual(out.returncode, 0, out.stderr)
            with open(png, "rb") as f:
                self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n")
            self.assertGreater(os.path.getsize(png), 20000)
        text = out.stdout
        got = dict(line.split(" ", 1) for line in text[:text.index("panel ")].splitlines())
        self.assertEqual(got["final_state"], "19 Alarm")
        self.assertEqual(got["samples"], "300 duration 1.495")
        self.assertEqual(text[text.index("panel "):], DESCRIBE_SIM)

    def test_describe_a_record(self):
        """vehiclectl record: measured only; the panels without data say so."""
        with tempfile.TemporaryDirectory() as tmp:
            rec = os.path.join(tmp, "rec.csv")
            with open(rec, "w") as f:
                f.write("t_s,state,msg,x_mm,y_mm,theta_deg,speed_mm_s,speed_deg_s,"
                        "battery_0_1V,alarms,newest_alarm\n")
                for i in range(20):
                    x = min(i, 10) * 20.0
                    f.write("%.3f,%d,%s,%.3f,0.000,0.000,%.3f,0.000,252.0,%d,%d\n" % (
                        i * 0.2, 17 if i < 10 else 18, "Busy" if i < 10 else "Warning",
                        x, 100.0 if 0 < i <= 10 else 0.0, int(i >= 10), 153 if i >= 10 else 0))
            out = subprocess.run(["/usr/bin/python3", os.path.join(TOP, "tools/vehicle-plot"),
                                  rec, "--describe"], capture_output=True, text=True, timeout=120)
            self.assertEqual(out.returncode, 0, out.stderr)
        text = out.stdout
        got = dict(line.split(" ", 1) for line in text[:text.index("panel ")].splitlines())
        self.assertEqual(got["peak_measured_velocity"], "100.000 0.000")
        self.assertNotIn("peak_velocity", got)
        self.assertEqual(got["final_state"], "18 Warning")
        self.assertEqual(text[text.index("panel "):], DESCRIBE_RECORD)

    def test_needs_an_output_or_describe(self):
        out = subprocess.run(["/usr/bin/python3", os.path.join(TOP, "tools/vehicle-plot"),
                              "x.csv"], capture_output=True, text=True, timeout=60)
        self.assertEqual(out.returncode, 2)
        self.assertEqual(out.stderr.splitlines()[-1],
                         "vehicle-plot: error: -o FILE or --describe")

    def test_bad_input(self):
        with tempfile.TemporaryDirectory() as tmp:
            bad = os.path.join(tmp, "bad.csv")
            with open(bad, "w") as f:
                f.write("a,b\n1,2\n")
            out = subprocess.run(["/usr/bin/python3", os.path.join(TOP, "tools/vehicle-plot"),
                                  bad, "-o", os.path.join(tmp, "x.png")],
                                 capture_output=True, text=True, timeout=60)
            self.assertEqual(out.returncode, 1)
            self.assertIn("neither a vehicle-sim trace nor a vehiclectl record", out.stderr)
            self.assertFalse(os.path.exists(os.path.join(tmp, "x.png")))


if __name__ == "__main__":
    unittest.main()
