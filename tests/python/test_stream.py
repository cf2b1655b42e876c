"""The telemetry stream from Python (Vehicle.subscribe: an iterator of typed
Samples) against vehicle-sim --pty; the package's table against
proto/stream.def; vehiclectl record over the stream and vehicle-plot
drawing that recording."""
import os
import re
import subprocess
import tempfile
import unittest

import vehicleservice as vs
from vehicleservice import plot, stream
from simrig import BUILD, FRAMES, TOP, Sim

TYPES = {"I16": "h", "I32": "i", "U8": "B", "U16": "H", "U32": "I"}


class Table(unittest.TestCase):
    def test_rows_match_stream_def(self):
        rows = []
        with open(os.path.join(TOP, "proto/stream.def")) as f:
            for line in f:
                m = re.match(r'STREAM_FIELD\((\w+),\s*(\w+),\s*(\w+),', line)
                if m:
                    rows.append((m.group(1), m.group(2).lower(), TYPES[m.group(3)]))
        self.assertEqual(rows, [(n, g, c) for n, g, c, _ in stream.FIELDS])
        self.assertEqual(stream.frame_bytes(stream.MASK_ALL), 52)
        self.assertEqual(stream.frame_bytes(stream.mask_of(("pose", "state"))), 28)

    def test_decode(self):
        # docs/protocol.md's example: seq 5, tick 12345, pose 1000.0 -2.5 90.0, Busy, 1 alarm
        payload = bytes.fromhex("0900393000001027" "0000E7FFFFFF905F010011 0001".replace(" ", ""))
        mask, tick, raw = stream.decode(payload)
        self.assertEqual((mask, tick), (9, 12345))
        self.assertEqual(raw, {"x_dmm": 10000, "y_dmm": -25, "theta_mdeg": 90000, "state": 0x11,
                               "alarms": 1})
        with self.assertRaises(ValueError):
            stream.decode(payload[:-1])


class Subscribe(unittest.TestCase):
    def setUp(self):
        self.sim = Sim(watchdog=False)
        self.v = vs.open_frames(self.sim.path, **FRAMES)

    def tearDown(self):
        self.v.close()
        self.sim.close()

    def test_samples_rate_and_requests_between(self):
        with self.v.subscribe(("pose", "state"), period_ms=20) as sub:
            self.assertEqual(sub.info, vs.StreamInfo(mask=9, period_ms=20, frame_bytes=28,
                                                     min_period_ms=4, tick_hz=1000))
            got = []
            for s in sub:
                if len(got) % 7 == 3:
                    self.assertEqual(self.v.getState().value.code, 25)
                got.append(s)
                if len(got) == 30:
                    break
        self.assertEqual([s.seq for s in got], list(range(30)))
        self.assertEqual([s.tick - got[0].tick for s in got], [20 * k for k in range(30)])
        self.assertEqual([s.t for s in got], [20 * k / 1000 for k in range(30)])
        self.assertTrue(all(isinstance(s, vs.Sample) for s in got))
        s = got[-1]
        self.assertEqual((s.lost, s.mask, s.state, s.alarms), (0, 9, 25, 0))
        self.assertEqual((s.x, s.y, s.theta), (0.0, 0.0, 0.0))
        self.assertIsNone(s.battery_V)  # not subscribed
        self.assertEqual(self.sim.console("$stream"),
                         "ok stream mask 0x00 period 0 sent 0 skipped 0")

    def test_refused_rate(self):
        with self.assertRaises(vs.NakError) as e:
            self.v.subscribe("all", period_ms=6)
        self.assertEqual((e.exception.status, e.exception.name), (8, "rate"))
        sub = self.v.subscribe("all", period_ms=7)
        self.assertEqual(sub.info.frame_bytes, 52)
        s = next(sub)
        self.assertEqual(s.mask, 0xFF)
        self.assertAlmostEqual(s.battery_V, self.v.getBatteryVoltage().value / 10, delta=0.006)
        sub.close()

    def test_content_at_rest_equals_getPosition(self):
        self.v.setPower(True)
        self.v.setServo(True)
        self.v.moveForward(123.4)
        self.v.wait_done(timeout=30)
        pos = self.v.getPosition().value
        with self.v.subscribe(("pose", "state", "queue"), period_ms=50) as sub:
            s = next(sub)
        self.assertEqual(s.x, round(pos.x * 10) / 10)
        self.assertEqual(s.y, round(pos.y * 10) / 10)
        self.assertEqual(s.theta, round(pos.theta * 1000) / 1000)
        self.assertEqual((s.state, s.queue), (self.v.getState().value.code, 0))


class Record(unittest.TestCase):
    def test_record_over_the_stream_and_plot(self):
        sim = Sim(watchdog=False)
        try:
            with vs.open_frames(sim.path, **FRAMES) as v:
                v.setPower(True)
                v.setServo(True)
                v.moveForward(1000.0)  # 3 s: 1 s up to 500 mm/s, 1 s at it, 1 s down
            with tempfile.TemporaryDirectory() as tmp:
                rec = os.path.join(tmp, "rec.csv")
                out = subprocess.run([os.path.join(BUILD, "vehiclectl"), "--port", sim.path,
                                      "record", rec, "--duration", "1.5", "--interval", "50"],
                                     capture_output=True, text=True, timeout=60)
                self.assertEqual(out.returncode, 0, out.stderr)
                cols, kind = plot.read_trace(rec)
                self.assertEqual(kind, "stream")
                self.assertEqual(cols["t_s"], [round(k * 0.05, 3) for k in range(31)])
                self.assertEqual(cols["seq"], list(range(31)))
                self.assertEqual(cols["lost"], [0.0] * 31)
                self.assertLessEqual(max(cols["cmd_vx_mm_s"]), 500.0)
                self.assertGreater(max(cols["meas_vx_mm_s"]), 100.0)
                png = os.path.join(tmp, "rec.png")
                out = subprocess.run(["/usr/bin/python3", os.path.join(TOP, "tools/vehicle-plot"),
                                      rec, "-o", png, "--describe"],
                                     capture_output=True, text=True, timeout=120)
                self.assertEqual(out.returncode, 0, out.stderr)
                with open(png, "rb") as f:
                    self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n")
                text = out.stdout
                self.assertIn("samples 31 duration 1.500\n", text)
                self.assertIn("panel translation velocity\n  x: t (s)\n  y: speed (mm/s)\n"
                              "  line commanded: solid\n  line measured: solid\n", text)
                self.assertIn("note: no wheel speeds in a vehiclectl record", text)
        finally:
            sim.close()


if __name__ == "__main__":
    unittest.main()
