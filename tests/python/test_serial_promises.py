"""The serial link's documented promises (docs/protocol.md, docs/console.md)
end to end on vehicle-sim --pty, with raw bytes and the Python client."""
import time
import unittest

import serial

import vehicleservice as vs
from simrig import CONSOLE, FRAMES, Sim
from vehicleservice.transport import FrameTransport


def read_for(port, seconds, want=0):
    """What arrives until `want` bytes are in (a loaded host may take up to
    15 s to answer) and then `seconds` pass with nothing more."""
    limit, got = time.monotonic() + 15, b""
    end = time.monotonic() + seconds
    while time.monotonic() < end or (len(got) < want and time.monotonic() < limit):
        port.timeout = 0.02
        b = port.read(4096)
        if b:
            got += b
            end = max(end, time.monotonic() + 0.1)
    return got


class Promises(unittest.TestCase):
    def setUp(self):
        self.sim = Sim()
        self.port = serial.Serial(self.sim.path, timeout=0.05)

    def tearDown(self):
        self.port.close()
        self.sim.close()

    def raw(self, data, want, seconds=0.3):
        self.port.write(data)
        return read_for(self.port, seconds, want)

    def test_naks_echo_the_seq(self):
        # declared length 200, seq 0x53: oversize, op 0x80, seq 0x53
        self.assertEqual(self.raw(bytes.fromhex("A5C800530B"), 8),
                         bytes.fromhex("A501005380021987"))
        # length 8, seq 0x52, then silence: truncated with seq 0x52
        self.assertEqual(self.raw(bytes.fromhex("A5080052"), 8, 0.5),
                         bytes.fromhex("A501005280 06ADF0".replace(" ", "")))
        # opcode 0x00: NAK opcode with op 0x80
        ans = self.raw(FrameTransport.encode(0x44, 0x00, b""), 8)
        self.assertEqual(ans[:6], bytes.fromhex("A50100448004"))

    def test_utf8_comment_is_a_comment(self):
        # "# café ¥ yen": ¥ is C2 A5, the sync byte
        got = self.raw("# café ¥ yen\ngetState\n".encode(), 23)
        self.assertEqual(got, b'ok true 25 "Unpowered"\n')  # LF only, no NAK
        got = self.raw("getState ¥\n".encode(), 28)
        self.assertEqual(got, b"error 7 binary data in line\n")
        with vs.open_frames(self.port, **FRAMES) as v:  # frames still work after it
            self.assertEqual(v.getState(), (True, (25, "Unpowered")))

    def test_console_after_a_naked_frame(self):
        bad = bytearray(FrameTransport.encode(0x21, 0x0B, b""))
        bad[-1] ^= 0xFF
        self.assertNotIn(b"\n", bad[1:])
        self.assertNotIn(b"\r", bad[1:])
        nak = self.raw(bytes(bad), 8)
        self.assertEqual(nak[:6], bytes.fromhex("A50100218001"))  # crc, seq echoed
        # the documented recovery: a bare LF, then the next request's reply
        # after the error 7 of the bad frame's bytes
        self.assertEqual(self.raw(b"\ngetState\n", 51),
                         b'error 7 binary data in line\nok true 25 "Unpowered"\n')

    def test_wait_is_refused_in_real_time(self):
        with vs.open_console(self.port, **CONSOLE) as c:
            with self.assertRaises(vs.ConsoleError) as e:
                c.transport.command("$wait 500")
            self.assertEqual(e.exception.code, 8)
            self.assertEqual(e.exception.message,
                             "$wait runs simulated time only with --fast; in real time the "
                             "host waits")
        # refused, not waited: the refusal came without the 500 ms (a
        # loaded host may add its own delay, so only the unit's answer is
        # asserted), and frames still work right after it
        with vs.open_frames(self.port, **FRAMES) as v:
            self.assertEqual(v.getState(), (True, (25, "Unpowered")))

    def test_link_counters(self):
        with vs.open_frames(self.port, **FRAMES) as v:
            v.getState()
            v.getState()
            with self.assertRaises(vs.NakError):
                v.transport.exchange(0x55, b"")
        self.port.write(b"\n$link\n")
        line = read_for(self.port, 0.3, 89)
        # info + 2 getState + 1 NAKed, all with a good check
        self.assertEqual(line, b"ok frames 4 executed 3 duplicates 0 naks 1 crc 0 oversize 0 "
                               b"truncated 0 other 7 txdrop 0\n")


if __name__ == "__main__":
    unittest.main()
