"""vehicle-plot renders a vehicle-sim trace: PNG and SVG files of a sane
size, and the limits and peaks it prints are those of the configuration and
of the trace (computed here independently)."""
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
