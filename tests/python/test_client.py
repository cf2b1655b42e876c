"""The Python client (python/vehicleservice), written from the documents,
against vehicle-sim --pty: every operation over binary frames and over the
console with the same results, cross-checked with the C client
(vehiclectl), and its exceptions for error lines, NAKs and timeouts."""
import json
import threading
import os
import time
import unittest

import serial

import vehicleservice as vs
from simrig import CONSOLE, FRAMES, Sim, vehiclectl


def wait_idle(v):
    for _ in range(400):
        if v.getState().value.code != 17:  # Busy
            time.sleep(0.3)  # the wheels settle on the end of the path
            return
        time.sleep(0.02)
    raise AssertionError("unit stayed busy")


# Every operation once, in an order whose results do not depend on timing
# (each motion is waited out before the next reading).
SCRIPT = [
    ("getVersion",), ("getIFVersion",), ("getState",), ("getBatteryVoltage",),
    ("getAccelerationLimit",), ("getVelocityLimit",), ("getDefaultAcceleration",),
    ("getDefaultVelocity",), ("getServoStatus", 0), ("getServoStatus", 9),
    ("moveForward", 100.0), ("getActiveAlarm", 5), ("clearAlarm",),
    ("setPower", True), ("setServo", True), ("getServoStatus", 1), ("getState",),
    ("setVelocity", 400.0, 80.0), ("setAcceleration", 800.0, 200.0),
    ("setJogTimeout", 300), ("setDigitalSensorLock", False), ("setJoystick", False),
    ("setOutput", 5, 1, 1), ("getInput", 1), ("getInput", 99), ("setOutput", 99, 1, 1),
    ("moveForward", 200.0), "wait", ("getPosition",),
    ("moveTurn", 90.0), "wait", ("getPosition",),
    ("moveLinearRel", 0.0, 100.0, 0.0), "wait", ("getPosition",),
    ("moveLinearAbs", 0.0, 0.0, 0.0), "wait", ("getPosition",),
    ("moveCircularRel", 0.0, 100.0, 90.0), ("moveCruiseAbs", 100.0, 0.0),
    ("moveContinuousRel", 50.0, 0.0, 0.0), "wait", ("stop",), "wait",
    ("setPosition", 10.0, 20.0, 30.0), ("getPosition",),
    ("moveJog", 0.0, 5.0, 0.0), ("pause",), ("getState",), ("resume",), ("unlock",),
    ("getActiveAlarm", 16), ("getActiveAlarm", -1), ("getActiveAlarm", 0),
]


def run_script(v):
    out = []
    for step in SCRIPT:
        if step == "wait":
            wait_idle(v)
            continue
        out.append((step, getattr(v, step[0])(*step[1:])))
    return out


def close(a, b, tol=0.0005 + 1e-9):
    """Console doubles have three decimals. Poses after motion are compared
    to 0.05 (mm, deg): in real time the plant's settling depends on when a
    command lands in its tick."""
    if isinstance(a, float):
        return abs(a - b) <= tol
    if isinstance(a, tuple) or isinstance(a, list):
        return len(a) == len(b) and all(close(x, y, tol) for x, y in zip(a, b))
    return a == b


class Client(unittest.TestCase):
    def setUp(self):
        self.sims = []

    def tearDown(self):
        for s in self.sims:
            s.close()

    def sim(self):
        s = Sim(watchdog=False)
        self.sims.append(s)
        return s

    def test_table_matches_unit(self):
        with vs.open_frames(self.sim().path, **FRAMES) as v:
            self.assertEqual(vs.table_crc(), 0x1F09)
            self.assertEqual(v.protocol_info(), (1, 0x1F09, 34, 24, 1108))

    def test_all_operations_frames_console_and_c_client(self):
        sf, sc = self.sim(), self.sim()
        with vs.open_frames(sf.path, **FRAMES) as v, vs.open_console(sc.path, **CONSOLE) as c:
            covered = {step[0] for step in SCRIPT if step != "wait"}
            self.assertEqual(covered, set(vs.OPERATIONS))
            res = {}
            th = threading.Thread(target=lambda: res.update(co=run_script(c)))
            th.start()
            fr = run_script(v)
            th.join()
            co = res["co"]
            for (step, a), (_, b) in zip(fr, co):
                tol = 0.05 if step == ("getPosition",) else 0.0005 + 1e-9
                self.assertTrue(close(a, b, tol), "%r: frames %r, console %r" % (step, a, b))
            got = dict((s, r) for s, r in fr)
            self.assertEqual(got[("getVersion",)], (True, "Ver.1.0.0"))
            self.assertEqual(got[("getIFVersion",)],
                             (True, "RTC VehicleService interface: ver.2.0.0"))
            self.assertEqual(got[("getAccelerationLimit",)], (True, (1000.0, 360.0)))
            self.assertEqual(got[("getVelocityLimit",)], (True, (1000.0, 180.0)))
            self.assertEqual(got[("getDefaultAcceleration",)], (True, (500.0, 180.0)))
            self.assertEqual(got[("getDefaultVelocity",)], (True, (500.0, 90.0)))
            self.assertEqual(got[("getServoStatus", 9)], (False, False))
            self.assertEqual(got[("getServoStatus", 1)], (True, True))
            self.assertEqual(got[("getInput", 1)], (True, 1))
            self.assertEqual(got[("getInput", 99)], (False, 0))
            self.assertIs(got[("setOutput", 99, 1, 1)], False)
            # setPosition sets odometry; the wheels may still settle by µm
            self.assertTrue(close(got[("getPosition",)].value, (10.0, 20.0, 30.0), 0.05))
            self.assertEqual(got[("getState",)].value, (21, "Paused"))
            self.assertIs(got[("moveJog", 0.0, 5.0, 0.0)], False)  # no sideways on 2 wheels
            count = got[("getActiveAlarm", 16)].value.count
            self.assertEqual(got[("getActiveAlarm", -1)], (True, (count, [])))
            self.assertEqual(got[("getActiveAlarm", 0)], (True, (count, [])))
            self.assertTrue(all(isinstance(a, vs.Alarm)
                                for a in got[("getActiveAlarm", 16)].value.alarms))
            self.assertEqual(fr[2][1], (True, (25, "Unpowered")))
            # the first moveForward was refused: warning 121 "servo off" or 120
            first = fr[11][1].value.alarms[0]
            self.assertEqual((first.type, first.source[:26]), (2, "moveForward refused: servo"))
            # the C client reads the same unit the same way (the pose to
            # 0.05: the wheels may still settle by µm between two reads)
            v.close()
            rc, out = vehiclectl(sf.path, "getPosition")
            self.assertEqual(rc, 0)
            j = json.loads(out)
            with vs.open_frames(sf.path, **FRAMES) as v2:
                p = v2.getPosition().value
                self.assertTrue(close(tuple(float(j[k]) for k in ("x", "y", "theta")), tuple(p),
                                      0.05), "%r %r" % (j, p))
                rc, out = vehiclectl(sf.path, "getDefaultAcceleration")
                j = json.loads(out)
                self.assertEqual((j["result"], j["translation"], j["rotation"]),
                                 (True, *v2.getDefaultAcceleration().value))
                rc, out = vehiclectl(sf.path, "getState")
                j = json.loads(out)
                self.assertEqual((j["state"], j["Msg"]), tuple(v2.getState().value))
                rc, out = vehiclectl(sf.path, "getActiveAlarm", 16)
                j = json.loads(out)
                al = v2.getActiveAlarm(16).value
                self.assertEqual(j["numOfActiveAlarm"], al.count)
                self.assertEqual([(a["code"], a["type"], a["source"]) for a in j["activeAlarms"]],
                                 [(a.code, str(a.type), a.source) for a in al.alarms])

    def test_errors_naks_timeouts(self):
        s = self.sim()
        with vs.open_frames(s.path, **FRAMES) as v:
            t = v.transport
            with self.assertRaises(vs.NakError) as e:
                t.exchange(0x55, b"")
            self.assertEqual((e.exception.status, e.exception.name), (4, "opcode"))
            with self.assertRaises(vs.NakError) as e:
                t.exchange(0x11, b"\0" * 7)  # moveForward with 7 bytes
            self.assertEqual(e.exception.status, 3)
            with self.assertRaises(vs.NakError) as e:
                t.exchange(0x1E, b"\x02")  # setPower 2
            self.assertEqual(e.exception.status, 5)
            with self.assertRaises(ValueError):
                v.setJogTimeout(40000)  # not a short: refused before sending
        with vs.open_console(s.path, **CONSOLE) as c:
            with self.assertRaises(vs.ConsoleError) as e:
                c.transport.command("moveForward 1 2")
            self.assertEqual(e.exception.code, 2)
            self.assertEqual(e.exception.message, "moveForward takes 1 argument, got 2")
            with self.assertRaises(vs.ConsoleError) as e:
                c.moveForward(float("nan"))
            self.assertEqual(e.exception.code, 3)
        # nobody answers: LinkTimeout after every retry
        m, sl = os.openpty()
        port = serial.Serial(os.ttyname(sl), timeout=0.05)
        t0 = time.monotonic()
        with self.assertRaises(vs.LinkTimeout):
            vs.open_frames(port, timeout=0.1, retries=1)
        self.assertGreaterEqual(time.monotonic() - t0, 0.2)
        port.close()
        os.close(m)
        os.close(sl)


if __name__ == "__main__":
    unittest.main()
