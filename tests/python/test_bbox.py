"""The black box over the serial link, in lockstep (vehicle-sim --pty
--fast: time advances only in $wait): a following error 204 with the trace
running on the same run. The Python client's read equals the trace's rows
for the same ticks column for column; vehicle-sim's --bbox-file, vehiclectl
bbox and the client's write are the same bytes; vehicle-plot marks the
fault; clear empties and re-arms; an empty box reads as a header alone."""
import csv
import io
import os
import subprocess
import tempfile
import unittest

import vehicleservice as vs
from simrig import BUILD, FRAMES, TOP
from vehicleservice import plot


class BlackBoxRun(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.trace = os.path.join(self.tmp.name, "trace.csv")
        self.fw_file = os.path.join(self.tmp.name, "fw.csv")
        self.proc = subprocess.Popen(
            [os.path.join(BUILD, "vehicle-sim"), "--pty", "--fast",
             "--config", os.path.join(TOP, "config/vehicle.xml"),
             "--io", os.path.join(TOP, "config/io.xml"),
             "--trace", self.trace, "--bbox-file", self.fw_file],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
        self.path = self.proc.stdout.readline().decode().strip()
        self.assertTrue(self.path.startswith("/dev/"))

    def tearDown(self):
        self.proc.stdin.close()
        self.proc.wait(20)
        self.proc.stdout.close()
        self.tmp.cleanup()

    def line(self, text, want):
        self.proc.stdin.write((text + "\n").encode())
        self.proc.stdin.flush()
        self.assertEqual(self.proc.stdout.readline().decode().rstrip("\n"), want)

    def fault(self):
        for text, want in (("$watchdog 0", "ok watchdog 0"), ("setPower true", "ok true"),
                           ("setServo true", "ok true"), ("moveForward 3000", "ok true"),
                           ("$wait 2500", "ok wait 2500"),
                           ("$sim drive 0 stuck", "ok drive 0 stuck"),
                           ("$wait 300", "ok wait 300")):
            self.line(text, want)

    def vehiclectl(self, *args):
        return subprocess.run([os.path.join(BUILD, "vehiclectl"), "--port", self.path,
                               "--timeout", "5000"] + list(args),
                              capture_output=True, text=True, timeout=60)

    def test_read_equals_the_trace(self):
        self.fault()
        with vs.open_frames(self.path, **FRAMES) as v:
            box = v.read_bbox()
        self.assertEqual((box.status, box.capacity, box.every, box.tick_hz, box.fault),
                         ("frozen", 2000, 1, 1000, 204))
        # the following error trips 101 ticks after the encoder stops
        self.assertEqual(box.trigger, 2601)
        self.assertEqual([s.tick for s in box.samples], list(range(602, 2602)))
        self.assertEqual(box.samples[-1].state, 19)
        self.assertEqual(box.samples[-1].newest_alarm, 204)
        with open(self.trace) as f:
            trace = list(csv.DictReader(f))
        rows = list(csv.DictReader(io.StringIO("\n".join(box.rows()))))
        shared = [c for c in rows[0] if c in trace[0]]
        self.assertEqual(len(shared), 22)
        for r in rows:
            t = trace[int(r["tick"]) - 1]
            self.assertEqual({c: r[c] for c in shared}, {c: t[c] for c in shared})
        mine = os.path.join(self.tmp.name, "py.csv")
        box.write(mine)
        ctl = os.path.join(self.tmp.name, "ctl.csv")
        out = self.vehiclectl("bbox", ctl)
        self.assertEqual(out.returncode, 0, out.stderr)
        self.assertEqual(out.stdout, "bbox frozen: 2000 samples, one every 1 ticks at 1000 Hz, "
                                     "fault 204 at tick 2601\n")
        with open(self.fw_file) as a, open(mine) as b, open(ctl) as c:
            fw = a.read()
            self.assertEqual(b.read(), fw)
            self.assertEqual(c.read(), fw)
        self.assertEqual(fw.splitlines()[-1].split(",")[-2:], ["2601", "204"])

        # vehicle-plot: a black box drawn as a trace, the fault marked
        text = io.StringIO()
        a = plot.plot(self.fw_file, [os.path.join(self.tmp.name, "b.svg")],
                      plot.read_config(None), out=text, describe_to=text)
        self.assertEqual(a["fault"], (2.601, 204))
        self.assertIn("fault 204 at 2.601000\n", text.getvalue())
        self.assertEqual(text.getvalue().count("  line fault 204: solid\n"), 7)
        self.assertIn("samples 2000 duration 1.999\n", text.getvalue())

    def test_clear_and_empty(self):
        self.fault()
        out = self.vehiclectl("bbox", "clear")
        self.assertEqual(out.stdout, "bbox armed: 0 samples, one every 1 ticks at 1000 Hz, "
                                     "fault 0 at tick 0\n")
        with vs.open_frames(self.path, **FRAMES) as v:
            box = v.read_bbox()
            self.assertEqual((box.status, box.trigger, box.fault, box.samples),
                             ("armed", 0, 0, []))
            empty = os.path.join(self.tmp.name, "empty.csv")
            self.assertEqual(self.vehiclectl("bbox", empty).returncode, 0)
            with open(empty) as f:
                self.assertEqual(f.read(), vs.bbox.COLUMNS + "\n")
            self.line("$wait 5", "ok wait 5")
            box = v.read_bbox()
            self.assertEqual([s.tick for s in box.samples], [2801, 2802, 2803, 2804, 2805])
            self.assertEqual(v.console_line("$bbox"), "bbox armed samples 5 of 2000 every 1 "
                             "tick_hz 1000 trigger 0 fault 0")
            v.clear_bbox()
            self.assertEqual(v.read_bbox().samples, [])
            # a bad index: NAK value
            with self.assertRaises(vs.NakError) as e:
                v.transport.exchange(vs.bbox.OP_BBOX, b"\x00\x01\x00")
            self.assertEqual(e.exception.name, "value")



class BlackBoxDoc(unittest.TestCase):
    def test_columns_are_documented_in_order(self):
        from test_trace_doc import documented
        self.assertEqual(documented("Black box"), vs.bbox.COLUMNS.split(","))


if __name__ == "__main__":
    unittest.main()
