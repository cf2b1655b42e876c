#!/usr/bin/python3
"""The product image's Modbus drives, watchdog and fault handler on QEMU's
mps2-an386 (docs/mcu.md, "Drives over RS-485 Modbus RTU").

The board's second UART (CMSDK UART1, the RS-485 line) is a pty this
harness relays to the drives' peer on a second pty, recording every byte
the board sends: build/mbdrive-sim (the simulator vehicle-fw's Modbus
backend is tested against) or tests/mcu/mb_peer.py on Debian's pymodbus.
The console is UART0 as in mcu_test.py. The unit's time is instruction
time (-icount shift=6,align=on); the peers answer in host time, so every
bound here is in the board's ticks and generous against the host's
delays, and no case waits for a host deadline.

Cases:
 - move: servo on waits for both drives to report the stage on (status
   bit read over the bus), moveForward 300 ends Ready at 300 mm within the
   position window, the odometry being the drives' position registers;
   the drive cycle's period as measured and its computed value;
 - alarm: the drive sets its alarm register (0x31): fault 201 "drive 0
   fault 0x0031";
 - silent: the second drive stops answering: 202 "drive 1 not answering",
   exactly drive_timeout_ms (500) plus at most 2 ticks after its last
   sample, its first failed cycle counted with exactly 1 + 2 retries;
 - pymodbus: the same move against pymodbus's server;
 - watchdog (test image): $hang spins the main loop; the drives are told
   to disable (enable register 0x106 = 0 to each unit) before the board
   restarts; it comes up Unpowered with warning 157 "reset by the watchdog
   at 0x...", the address inside board_test_extra;
 - hardfault (test image): $fault reads an address nothing answers: the
   same, 157 "reset by a HardFault at 0x..." naming the faulting load.

One line per case, "ok NAME" or "FAIL NAME: why"; last line
"mcu-drives: N passed, M failed".

  /usr/bin/python3 tests/mcu/mcu_drives.py BUILD [CASE,...]
"""
import os
import re
import select
import subprocess
import sys
import tempfile
import threading
import time
import traceback
import tty

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mcu_test import Board, ICOUNT_SHIFT, REPLY_S, expect, position, symbol  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
# hal/cortexm/plant_modbus.c with the test image's timing (mk/cortexm.mk,
# MCU_TEST_DEFS)
DRIVE_TIMEOUT_MS = 5000
RETRIES = 1
CYCLE_CALC_US = 12507  # mbd_cycle_us: two drives at 115200 baud
COUNT_MM = 150 * 3.141592653589793 / 16384
WINDOW_MM = 0.05  # position_window_mm


def crc16(b):
    c = 0xFFFF
    for x in b:
        c ^= x
        for _ in range(8):
            c = (c >> 1) ^ 0xA001 if c & 1 else c >> 1
    return bytes([c & 0xFF, c >> 8])


def frame(*b):
    b = bytes(b)
    return b + crc16(b)


def request_len(b):
    """The length of the master's request at the start of b (0: not known
    yet; anything else is passed on a byte at a time)."""
    if len(b) < 2:
        return 0
    if b[1] in (3, 4, 6):
        return 8
    if b[1] == 16:
        return 9 + b[6] if len(b) >= 7 else 0
    return 1


class DriveBoard(Board):
    """The board with its drive line relayed to a peer."""

    def __init__(self, elf, tmp, name, peer_argv):
        self.elf = elf
        self.qmp_path = os.path.join(tmp, "qmp-%s.sock" % name)
        master, self.fd = os.openpty()
        tty.setraw(self.fd)
        self.pty = os.ttyname(self.fd)
        # the drive line: QEMU's end, and the peer's pty
        line, self.line = os.openpty()
        tty.setraw(self.line)
        self.peer_m, peer_s = os.openpty()
        tty.setraw(peer_s)
        tty.setraw(self.peer_m)
        self.peer_path = os.ttyname(peer_s)
        self.peer_keep = peer_s
        self.rx = b""
        self.qmp = None
        self.proc = None
        self.sent = bytearray()  # what the board sent on the line
        self.quiet = set()       # units whose answers the relay drops
        self.trace = []          # (host time, direction, frame): shown on a failure
        self.stop = False
        # The peer first, answering, then the board: its first requests
        # must not find a peer still starting.
        self.peer = subprocess.Popen([a.replace("PORT", self.peer_path) for a in peer_argv],
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     stderr=subprocess.STDOUT, text=True)
        self._probe()
        self.log = open(os.path.join(tmp, "qemu-%s.log" % name), "w+b")
        self.proc = subprocess.Popen(
            ["qemu-system-arm", "-M", "mps2-an386", "-nographic", "-monitor", "none",
             "-qmp", "unix:%s,server=on,wait=off" % self.qmp_path,
             "-add-fd", "fd=%d,set=1" % master, "-add-fd", "fd=%d,set=2" % line,
             "-chardev", "serial,id=uart,path=/dev/fdset/1", "-serial", "chardev:uart",
             "-chardev", "serial,id=rs485,path=/dev/fdset/2", "-serial", "chardev:rs485",
             "-icount", "shift=%d,align=on" % ICOUNT_SHIFT, "-kernel", elf],
            stdin=subprocess.DEVNULL, stdout=self.log, stderr=subprocess.STDOUT,
            pass_fds=(master, line), start_new_session=True)
        os.close(master)
        os.close(line)
        self.relay = threading.Thread(target=self._relay, daemon=True)
        self.relay.start()
        deadline = time.monotonic() + 30
        while not os.path.exists(self.qmp_path):
            if self.proc.poll() is not None or time.monotonic() > deadline:
                raise RuntimeError("qemu did not start")
            time.sleep(0.05)

    def _probe(self):
        """Asks the peer for unit 1's status register until it answers."""
        req = frame(1, 3, 0x01, 0x04, 0, 1)
        deadline = time.monotonic() + REPLY_S
        got = b""
        while len(got) < 7:
            assert time.monotonic() < deadline, "the peer does not answer"
            os.write(self.peer_m, req)
            got = b""
            end = time.monotonic() + 0.5
            while len(got) < 7 and time.monotonic() < end:
                if select.select([self.peer_m], [], [], 0.05)[0]:
                    got += os.read(self.peer_m, 64)
        time.sleep(0.1)
        while select.select([self.peer_m], [], [], 0)[0]:
            os.read(self.peer_m, 64)

    def _relay(self):
        # Whole frames to the peer: the emulated core pauses to stay in step
        # with the host's clock (align=on), and a pause between two bytes of
        # one frame would reach the peer as a gap, which a wire does not
        # have (the UART sends a frame's bytes back to back).
        pend = b""
        while not self.stop:
            r, _, _ = select.select([self.line, self.peer_m], [], [], 0.1)
            if self.line in r:
                b = os.read(self.line, 4096)
                self.sent += b
                pend += b
                while True:
                    n = request_len(pend)
                    if n == 0 or len(pend) < n:
                        break
                    os.write(self.peer_m, pend[:n])
                    self.trace.append((time.monotonic(), ">", pend[:n].hex()))
                    pend = pend[n:]
            if self.peer_m in r:
                b = os.read(self.peer_m, 4096)
                drop = b and b[0] in self.quiet
                self.trace.append((time.monotonic(), "x" if drop else "<", b.hex()))
                if not drop:
                    os.write(self.line, b)

    def close(self):
        self.stop = True
        if self.proc:
            self.relay.join(2)
            super().close()
        self.peer.terminate()
        self.peer.wait(10)
        for fd in (self.line, self.peer_m, self.peer_keep):
            os.close(fd)

    # ---- the board's state through the monitor -----------------------------
    def words(self, name, n, off=0):
        out = self.monitor("xp /%dwx 0x%x" % (n, symbol(self.elf, name) + off))
        return [int(x, 16) for x in re.findall(r"\b0x([0-9a-f]{8})\b", out)][:n]

    def bus(self):
        """plant_bus (mbd_bus_t, hal/modbus/mbmaster.h): the master's
        counters, the drives' samples and failures, the cycle's period."""
        # mbd_bus_t: four words of the cycle, then mbm_t, its counters first
        c = self.words("plant_bus", 8, 16)
        return {"requests": c[0], "retries": c[1], "timeouts": c[2], "crc": c[3],
                "bad": c[4], "exceptions": c[5], "busy": c[6], "illegal": c[7]}

    def wait_state(self, want, ms):
        end = self.now() + ms
        while True:
            r = self.ex("getState")
            if r == want:
                return
            assert self.now() < end, "%r after %d ms: %r" % (want, ms, r)
            time.sleep(0.02)


SIM = ["BUILD/mbdrive-sim", "--port", "PORT", "--units", "1,2", "--set", "comm_timeout=0x109 u16"]
PYMODBUS = ["/usr/bin/python3", os.path.join(HERE, "mb_peer.py"), "PORT", "1", "2"]


def c_boot(b):
    expect(b, "getState", 'ok true 25 "Unpowered"')
    expect(b, "getActiveAlarm 4", "ok true 0 0")
    expect(b, "getBatteryVoltage", "ok true 240.000")


def move(b, mm):
    # The emulated line is slower than a wire (a sample every 100 to 400 ms
    # of the board's time: QEMU's UART and the host's load): the move runs
    # at 100 mm/s, the wheel loop's gain is low enough for that delay and
    # the supervision allows for it.
    for line, reply in (("$config encoder_stuck_ms 10000", "ok encoder_stuck_ms 10000"),
                        ("$config following_error_mm 1000", "ok following_error_mm 1000.000"),
                        ("$config settle_timeout_ms 10000", "ok settle_timeout_ms 10000"),
                        ("$config servo_on_timeout_ms 10000", "ok servo_on_timeout_ms 10000"),
                        ("$config wheel_kp_per_s 2", "ok wheel_kp_per_s 2.000"),
                        ("setVelocity 100 90", "ok true")):
        expect(b, line, reply)
    expect(b, "setPower true", "ok true")
    expect(b, "setServo true", "ok true")
    b.wait_state('ok true 16 "Ready"', 10000)
    expect(b, "getServoStatus 0", "ok true true")
    expect(b, "getServoStatus 1", "ok true true")
    expect(b, "moveForward %d" % mm, "ok true")
    b.wait_state('ok true 16 "Ready"', mm * 10 + 12000)
    x, y, th = position(b)
    assert abs(x - mm) <= WINDOW_MM + COUNT_MM and abs(y) <= WINDOW_MM + COUNT_MM \
        and abs(th) <= 0.01, "position %r after moveForward %d" % ((x, y, th), mm)


def c_move(b):
    move(b, 300)
    # the frames the board sent: the drives' communication stop (0x109 =
    # 5000 ms) first, each unit's enable, then the cycle
    assert b.sent.startswith(frame(1, 6, 0x01, 0x09, 0x13, 0x88)), b.sent[:16].hex()
    assert frame(2, 6, 0x01, 0x09, 0x13, 0x88) in b.sent
    assert frame(1, 6, 0x01, 0x06, 0, 1) in b.sent and frame(2, 6, 0x01, 0x06, 0, 1) in b.sent
    c = b.bus()
    assert c["crc"] == 0 and c["bad"] == 0 and c["exceptions"] == 0, c
    # the drive cycle: mbd_bus_t's cycle_us (last), cycle_worst_us, cycles
    cyc = b.words("plant_bus", 3)
    print("  drive cycle: last %d us, worst %d us, %d cycles (computed %d us at 115200 "
          "baud, two drives); master's worst poll %d cycles; %d requests, %d timeouts"
          % (cyc[0], cyc[1], cyc[2], CYCLE_CALC_US, b.words("plant_cost", 2)[1],
             c["requests"], c["timeouts"]))
    assert cyc[2] > 10


def c_alarm(b):
    expect(b, "setPower true", "ok true")
    b.wait(1000)
    b.peer.send_signal(__import__("signal").SIGUSR2)
    b.wait_state('ok true 19 "Alarm-201"', DRIVE_TIMEOUT_MS)
    expect(b, "getActiveAlarm 1", 'ok true 1 1 201 fault "drive 0 fault 0x0031"')


def c_silent(b):
    expect(b, "setPower true", "ok true")
    b.wait(1000)
    before = b.bus()
    b.quiet.add(2)
    b.wait_state('ok true 19 "Alarm-202"', 3 * DRIVE_TIMEOUT_MS)
    expect(b, "getActiveAlarm 1", 'ok true 1 1 202 fault "drive 1 not answering"')
    after = b.bus()
    # its first failed request: one attempt and 2 retries, each a timeout
    assert after["retries"] - before["retries"] >= RETRIES, (before, after)
    assert after["timeouts"] - before["timeouts"] >= 1 + RETRIES, (before, after)


def c_pymodbus(b):
    move(b, 200)
    c = b.bus()
    assert c["crc"] == 0 and c["bad"] == 0 and c["exceptions"] == 0, c


def restarted(b, cmd, why, handler):
    expect(b, "setPower true", "ok true")
    expect(b, "setServo true", "ok true")
    b.wait(1000)
    mark = len(b.sent)
    b.write(cmd.encode() + b"\n")
    # no reply to it: the board restarts; then it answers again, Unpowered
    deadline = time.monotonic() + REPLY_S
    while True:
        b.drain()
        assert time.monotonic() < deadline, "no restart"
        b.write(b"getState\n")
        r = b.readline()
        if r == 'ok true 25 "Unpowered"':
            break
        time.sleep(0.05)
    after = bytes(b.sent[mark:])
    # the drives told to disable before the restarted board's first frame
    # (its communication stop, 0x109)
    off1, off2 = frame(1, 6, 0x01, 0x06, 0, 0), frame(2, 6, 0x01, 0x06, 0, 0)
    boot = after.find(frame(1, 6, 0x01, 0x09, 0x13, 0x88))
    assert boot > 0, after.hex()
    assert 0 <= after.find(off1) < boot and 0 <= after.find(off2) < boot, after.hex()
    r = b.ex("getActiveAlarm 1")
    m = re.match(r'ok true 1 1 157 warning "reset by (the watchdog|a HardFault) at 0x([0-9a-f]{8})"$',
                 r)
    assert m and m.group(1) == why, r
    pc = int(m.group(2), 16)
    lo = symbol(b.elf, handler)
    assert lo <= pc < lo + 0x100, "pc 0x%x not in %s (0x%x)" % (pc, handler, lo)
    expect(b, "getPosition", "ok true 0.000 0.000 0.000")


def c_watchdog(b):
    restarted(b, "$hang", "the watchdog", "board_test_extra")


def c_hardfault(b):
    restarted(b, "$fault", "a HardFault", "board_test_extra")


def main():
    global BUILD
    BUILD = sys.argv[1] if len(sys.argv) > 1 else "build"
    elf = os.path.join(BUILD, "cortex-m4-mb", "vehicle-test.elf")
    passed = failed = 0
    sim = [a.replace("BUILD", BUILD) for a in SIM]
    plan = [("move", sim, c_move), ("alarm", sim, c_alarm), ("silent", sim, c_silent),
            ("pymodbus", PYMODBUS, c_pymodbus), ("watchdog", sim, c_watchdog),
            ("hardfault", sim, c_hardfault)]
    only = sys.argv[2].split(",") if len(sys.argv) > 2 else None
    plan = [p for p in plan if not only or p[0] in only]
    with tempfile.TemporaryDirectory() as tmp:
        for name, peer, fn in plan:
            t0 = time.monotonic()
            b = None
            try:
                b = DriveBoard(elf, tmp, name, peer)
                expect(b, "$watchdog 0", "ok watchdog 0")
                c_boot(b)
                fn(b)
                passed += 1
                print("ok %s (%.1f s)" % (name, time.monotonic() - t0), flush=True)
            except Exception as e:  # one case's failure must not hide the rest
                failed += 1
                print("FAIL %s: %s" % (name, e), flush=True)
                traceback.print_exc(limit=3, file=sys.stdout)
                if b:
                    try:
                        print("  then: %s | %s" % (b.ex("getActiveAlarm 4"), b.bus()))
                        t0 = b.trace[-40][0] if len(b.trace) >= 40 else 0
                        for t, d, h in b.trace[-40:]:
                            print("  %9.1f ms %s %s" % ((t - t0) * 1000, d, h))
                    except Exception as e2:
                        print("  no state after it: %s" % e2)
            finally:
                if b:
                    b.close()
    print("mcu-drives: %d passed, %d failed" % (passed, failed))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
