"""Vehicle.wait_done against vehicle-sim --pty, after a refused request left
a warning (the unit reads Warning-### while idle: done, spec 6.9), and the
alarms' type as a name (AlarmType) over frames and the console, the same
as vehiclectl writes it."""
import json
import unittest

import vehicleservice as vs
from simrig import CONSOLE, FRAMES, Sim, vehiclectl


class Wait(unittest.TestCase):
    def setUp(self):
        self.s = Sim(watchdog=False)

    def tearDown(self):
        self.s.close()

    def test_wait_done_after_a_warning(self):
        with vs.open_frames(self.s.path, **FRAMES) as v:
            self.assertTrue(v.setPower(True))
            self.assertTrue(v.setServo(True))
            self.assertIs(v.setVelocity(0.0, 10.0), False)
            self.assertEqual(v.getState().value, vs.State(18, "Warning-111"))
            self.assertTrue(v.moveForward(300.0))
            self.assertEqual(v.getState().value, vs.State(17, "Busy"))
            self.assertEqual(v.wait_done(timeout=60), vs.State(18, "Warning-111"))
            # done is in position: every wheel within the 0.05 mm window
            p = v.getPosition().value
            self.assertLessEqual(abs(p.x - 300.0), 0.05, p)

            # a fault while the move runs: MotionStopped with the fault
            self.assertTrue(v.moveForward(5000.0))
            self.assertEqual(self.s.console("$sim drive 1 fault 0x2310"),
                             "ok drive 1 fault 0x2310")
            with self.assertRaises(vs.MotionStopped) as e:
                v.wait_done(timeout=60)
            self.assertEqual(e.exception.state, vs.State(19, "Alarm-201"))
            self.assertEqual(e.exception.alarm, vs.Alarm(201, vs.AlarmType.fault,
                                                         "drive 1 fault 0x2310"))
            self.assertEqual(str(e.exception),
                             'stopped short: 19 Alarm-201 (201 fault "drive 1 fault 0x2310")')

            # still busy at the timeout: WaitTimeout; a stop is then done
            self.assertEqual(self.s.console("$sim drive 1 ok"), "ok drive 1 ok")
            self.assertTrue(v.clearAlarm())
            self.assertTrue(v.setServo(True))
            self.assertTrue(v.moveForward(5000.0))
            with self.assertRaises(vs.WaitTimeout) as e:
                v.wait_done(timeout=0.1)
            self.assertIsInstance(e.exception, TimeoutError)
            self.assertEqual(e.exception.state, vs.State(17, "Busy"))
            self.assertTrue(v.stop())
            self.assertEqual(v.wait_done(timeout=60), vs.State(16, "Ready"))

    def test_alarm_type_is_a_name(self):
        self.assertEqual([(t.name, int(t)) for t in vs.AlarmType],
                         [("unknown", 0), ("fault", 1), ("warning", 2)])
        w = vs.AlarmType.warning
        self.assertEqual((str(w), "%s" % w, "{}".format(w), "{:d}".format(w), "%d" % w),
                         ("warning", "warning", "warning", "2", "2"))
        self.assertTrue(w == 2 and isinstance(w, int))
        with vs.open_frames(self.s.path, **FRAMES) as v:
            self.assertIs(v.setServo(True), False)  # no power: warning 128
            fr = v.getActiveAlarm(4).value
        with vs.open_console(self.s.path, **CONSOLE) as c:
            co = c.getActiveAlarm(4).value
        want = vs.ActiveAlarms(1, [vs.Alarm(128, vs.AlarmType.warning,
                                            "setServo refused: power off")])
        self.assertEqual(fr, want)
        self.assertEqual(co, want)
        for a in fr.alarms + co.alarms:
            self.assertIs(a.type, vs.AlarmType.warning)
        rc, out = vehiclectl(self.s.path, "getActiveAlarm", 4)
        self.assertEqual(rc, 0)
        self.assertEqual([(a["code"], a["type"], a["source"]) for a in json.loads(out)["activeAlarms"]],
                         [(a.code, str(a.type), a.source) for a in fr.alarms])


if __name__ == "__main__":
    unittest.main()
