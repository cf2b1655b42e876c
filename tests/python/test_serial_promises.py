"""The serial link's documented promises (docs/protocol.md, docs/console.md)
end to end on vehicle-sim --pty, with raw bytes and the Python client."""
import time
import unittest

import serial

import vehicleservice as vs
from simrig import Sim
from vehicleservice.transport import FrameTransport


def read_for(port, seconds):
    end, got = time.monotonic() + seconds, b""
    while time.monotonic() < end:
        port.timeout = 0.02
        got += port.read(4096)
    return got


class Promises(unittest.TestCase):
    def setUp(self):
        self.sim = Sim()
        self.port = serial.Serial(self.sim.path, timeout=0.05)

    def tearDown(self):
        self.port.close()
        self.sim.close()

    def raw(self, data, seconds=0.3):
        self.port.write(data)
        return read_for(self.port, seconds)

    def test_naks_echo_the_seq(self):
        # declared length 200, seq 0x53: oversize, op 0x80, seq 0x53
        self.assertEqual(self.raw(bytes.fromhex("A5C800530B")),
                         bytes.fromhex("A501005380021987"))
        # length 8, seq 0x52, then silence: truncated with seq 0x52
        self.assertEqual(self.raw(bytes.fromhex("A5080052"), 0.5),
                         bytes.fromhex("A501005280 06ADF0".replace(" ", "")))
        # opcode 0x00: NAK opcode with op 0x80
        ans = self.raw(FrameTransport.encode(0x44, 0x00, b""))
        self.assertEqual(ans[:6], bytes.fromhex("A50100448004"))

    def test_utf8_comment_is_a_comment(self):
        # "# café ¥ yen": ¥ is C2 A5, the sync byte
        got = self.raw("# café ¥ yen\ngetState\n".encode())
        self.assertEqual(got, b'ok true 25 "Unpowered"\n')  # LF only, no NAK
        got = self.raw("getState ¥\n".encode())
        self.assertEqual(got, b"error 7 binary data in line\n")
        with vs.open_frames(self.port) as v:  # frames still work after it
            self.assertEqual(v.getState(), (True, (25, "Unpowered")))

    def test_console_after_a_naked_frame(self):
        bad = bytearray(FrameTransport.encode(0x21, 0x0B, b""))
        bad[-1] ^= 0xFF
        self.assertNotIn(b"\n", bad[1:])
        self.assertNotIn(b"\r", bad[1:])
        nak = self.raw(bytes(bad))
        self.assertEqual(nak[:6], bytes.fromhex("A50100218001"))  # crc, seq echoed
        # the documented recovery: a bare LF, then the next request's reply
        # after the error 7 of the bad frame's bytes
        self.assertEqual(self.raw(b"\ngetState\n"),
                         b'error 7 binary data in line\nok true 25 "Unpowered"\n')

    def test_wait_is_refused_in_real_time(self):
        with vs.open_console(self.port) as c:
            t0 = time.monotonic()
            with self.assertRaises(vs.ConsoleError) as e:
                c.transport.command("$wait 500")
            self.assertEqual(e.exception.code, 8)
            self.assertEqual(e.exception.message,
                             "$wait runs simulated time only with --fast; in real time the "
                             "host waits")
        # and the link is not held: a frame right after is answered at once
        # (the retry budget is below the old 500 ms stall)
        with vs.open_frames(self.port, timeout=0.2, retries=0) as v:
            self.assertEqual(v.getState(), (True, (25, "Unpowered")))
        self.assertLess(time.monotonic() - t0, 5)

    def test_link_counters(self):
        with vs.open_frames(self.port) as v:
            v.getState()
            v.getState()
            with self.assertRaises(vs.NakError):
                v.transport.exchange(0x55, b"")
        self.port.write(b"\n$link\n")
        line = read_for(self.port, 0.3)
        # info + 2 getState + 1 NAKed, all with a good check
        self.assertEqual(line, b"ok frames 4 executed 3 duplicates 0 naks 1 crc 0 oversize 0 "
                               b"truncated 0 other 7 txdrop 0\n")


if __name__ == "__main__":
    unittest.main()
