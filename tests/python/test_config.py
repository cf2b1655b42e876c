"""$config from Python (Vehicle.config, Vehicle.console_line) against
vehicle-sim --pty: over binary frames (console frames, docs/protocol.md)
and over the console, the same replies; refusals as ConsoleError."""
import unittest

import vehicleservice as vs
from simrig import CONSOLE, FRAMES, Sim


class Config(unittest.TestCase):
    def setUp(self):
        self.sim = Sim(watchdog=False)

    def tearDown(self):
        self.sim.close()

    def check(self, v):
        self.assertEqual(v.config("wheel_diameter_mm"), "wheel_diameter_mm 150.000")
        self.assertEqual(v.config("wheel_diameter_mm", 160), "wheel_diameter_mm 160.000")
        self.assertEqual(v.config("drive_lag_ms[1]", 25),
                         "drive_lag_ms 20.000 25.000 20.000 20.000")
        self.assertEqual(v.config("tick_hz", 500), "tick_hz 1000 pending 500")
        # $watchdog 0 (Sim) changed link_timeout_ms for the run
        self.assertEqual(v.config("diff"), "unsaved 4 tick_hz wheel_diameter_mm drive_lag_ms "
                                           "link_timeout_ms changed 4 tick_hz wheel_diameter_mm "
                                           "drive_lag_ms link_timeout_ms pending 1 tick_hz")
        self.assertEqual(v.config("store"), "store none table 0x916B11C3")
        with self.assertRaises(vs.ConsoleError) as e:
            v.config("save")
        self.assertEqual((e.exception.code, e.exception.message),
                         (8, "$config save: this unit has no store"))
        self.assertTrue(v.setPower(True))
        self.assertTrue(v.setServo(True))
        with self.assertRaises(vs.ConsoleError) as e:
            v.config("wheel_diameter_mm", 170)
        self.assertEqual((e.exception.code, e.exception.message),
                         (8, "$config wheel_diameter_mm: wheel_diameter_mm changes only with "
                             "the servo off and no motion queued"))
        self.assertTrue(v.setServo(False))
        self.assertEqual(v.config("defaults"), "defaults pending 0")
        self.assertEqual(v.console_line("$watchdog 0"), "watchdog 0")
        self.assertEqual(v.config("wheel_diameter_mm"), "wheel_diameter_mm 150.000")

    def test_frames(self):
        with vs.open_frames(self.sim.path, **FRAMES) as v:
            self.check(v)
            with self.assertRaises(ValueError):
                v.config("drive_lag_ms", *(["1.0000000000"] * 4), "x" * 20)

    def test_console(self):
        with vs.open_console(self.sim.path, **CONSOLE) as v:
            self.check(v)


if __name__ == "__main__":
    unittest.main()
