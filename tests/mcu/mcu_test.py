#!/usr/bin/python3
"""The Cortex-M image on QEMU's emulated board (docs/mcu.md).

Boots BUILD/cortex-m4/vehicle.elf on mps2-an386 (Cortex-M4, CMSDK UART,
25 MHz SysTick) with -icount shift=6,align=on, so that the unit's time is
instruction time: one instruction takes 64 ns of the unit's clock whatever
the host's load, and what a tick or a request costs is exact. align=on
keeps that clock from running ahead of the host's: the emulator pauses
instead, and its I/O thread runs. (With sleep=off the board, which polls
its UART and never sleeps, could hold QEMU's I/O off for seconds on a
loaded host: the UART's transmitter stalled, the board's ring filled and
replies were cut.) A loaded host makes the unit late, never fast.
Over the UART (a pty handed to QEMU's tty backend) it runs the console conformance
cases of tests/test_conformance.c that the board supports (its plant is the
loopback drives of hal/cortexm/loop_hal.c: no IO module, no relay, contact
or drive faults to inject, the reference wheel), then vehiclectl with binary
frames, then checks what each request and each tick cost on the board
(board_cost in hal/cortexm/board_main.c, read through QEMU's QMP monitor).

Then the configuration store across resets: $config save and a system
reset through the monitor, and a reset in the middle of a save
(vehicle-cut.elf, the store's cut hook), each on a fresh QEMU (an erased
store).

Then the Cortex-M0 image on mps2-an385: QEMU has no ARMv6-M board with this
UART, so a Cortex-M3 runs it; that proves it boots and answers, not that the
part's instruction set suffices.

One line per case, "ok NAME" or "FAIL NAME: why"; last line
"mcu: N passed, M failed".

  /usr/bin/python3 tests/mcu/mcu_test.py BUILD
"""
import csv
import json
import math
import os
import re
import select
import socket
import struct
import subprocess
import sys
import tempfile
import time
import traceback
import tty

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "python"))
from vehicleservice import stream as vs_stream  # noqa: E402
from vehicleservice.client import Vehicle  # noqa: E402
from vehicleservice.errors import NakError  # noqa: E402
from vehicleservice.transport import FrameTransport  # noqa: E402

ICOUNT_SHIFT = 6
CPU_HZ = 25000000
PERIOD_CYCLES = CPU_HZ // 1000
# One encoder count of the reference wheel (150 mm, 16384 counts/rev), mm,
# and the 0.001 mm of two readings rounded to three decimals.
COUNT_MM = 150 * 3.141592653589793 / 16384 + 0.001
# Host-time limit for one reply: the host's load stretches it, nothing else.
REPLY_S = 60


class Board:
    """One QEMU instance: the UART on a pty, the monitor on a QMP socket."""

    def __init__(self, elf, machine, tmp):
        self.elf = elf
        self.qmp_path = os.path.join(tmp, "qmp-%s.sock" % machine)
        # The UART is a pty this harness opens and hands to QEMU's tty
        # backend (-add-fd), not QEMU's own pty backend: that one takes a
        # read that finds nothing (EAGAIN, seen on a loaded host) for a
        # hang-up and drops what the board sends for up to a second. On a
        # tty, a full pty holds the UART's transmitter and nothing is lost.
        # QEMU's stdout (its "guest is late" warnings) goes to the log.
        master, self.fd = os.openpty()
        tty.setraw(self.fd)
        self.pty = os.ttyname(self.fd)
        self.log = open(os.path.join(tmp, "qemu-%s.log" % machine), "w+b")
        self.proc = subprocess.Popen(
            ["qemu-system-arm", "-M", machine, "-nographic", "-monitor", "none",
             "-qmp", "unix:%s,server=on,wait=off" % self.qmp_path,
             "-add-fd", "fd=%d,set=1" % master,
             "-chardev", "serial,id=uart,path=/dev/fdset/1", "-serial", "chardev:uart",
             "-icount", "shift=%d,align=on" % ICOUNT_SHIFT, "-kernel", elf],
            stdin=subprocess.DEVNULL, stdout=self.log, stderr=subprocess.STDOUT,
            pass_fds=(master,), start_new_session=True)
        os.close(master)
        self.rx = b""
        self.qmp = None
        deadline = time.monotonic() + 30
        while not os.path.exists(self.qmp_path):
            if self.proc.poll() is not None or time.monotonic() > deadline:
                self.log.seek(0)
                err = self.log.read()
                self.close()
                raise RuntimeError("qemu did not start: %r" % err)
            time.sleep(0.05)

    def close(self):
        if getattr(self, "fd", None) is not None:
            os.close(self.fd)
            self.fd = None
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.log.close()

    # ---- the UART ---------------------------------------------------------
    def write(self, data):
        # Paced: QEMU takes received bytes into the UART's one-byte holding
        # register as the guest reads them; small chunks keep the pty's
        # buffer from ever being the limit.
        for i in range(0, len(data), 16):
            os.write(self.fd, data[i:i + 16])
            time.sleep(0.002)

    def readline(self, timeout=REPLY_S):
        deadline = time.monotonic() + timeout
        while b"\n" not in self.rx:
            left = deadline - time.monotonic()
            if left <= 0:
                raise AssertionError("no reply within %d s (got %r)" % (timeout, self.rx))
            r, _, _ = select.select([self.fd], [], [], left)
            if r:
                self.rx += os.read(self.fd, 4096)
        line, self.rx = self.rx.split(b"\n", 1)
        return line.decode("latin-1")

    def ex(self, line):
        if isinstance(line, str):
            line = line.encode("latin-1")
        self.write(line + b"\n")
        return self.readline()

    def drain(self):
        """Anything left unread (there must be nothing)."""
        while select.select([self.fd], [], [], 0.2)[0]:
            self.rx += os.read(self.fd, 4096)
        left, self.rx = self.rx, b""
        return left

    # ---- the unit's time ----------------------------------------------------
    def ticks(self):
        m = re.match(r"ok ticks (\d+) overruns (\d+) ", self.ex("$diag"))
        assert m, "bad $diag reply"
        return int(m.group(1)), int(m.group(2))

    def now(self):
        """The unit's tick count, read through the monitor: no request, so
        the wait does not load the unit."""
        return self.costs()["ticks"]

    def wait(self, ms):
        """Lets ms of the unit's time pass (the simulator's $wait)."""
        end = self.now() + ms
        while True:
            now = self.now()
            if now >= end:
                return
            # Host time only paces the polling; the unit's clock decides.
            time.sleep(min(0.05, (end - now) / 4000.0))

    def settle(self, ms):
        """Waits until the unit is no longer Busy, which must happen within
        ms of its time, then 300 ms more for the wheel loop to settle (where
        the simulator's test waits a fixed time long enough for both)."""
        end = self.now() + ms
        while True:
            r = self.ex("getState")
            if not re.match(r'ok true \d+ "', r):
                # not a getState reply: a stalled host's leftovers (a frame
                # QEMU handed over late reaches the console); clear them
                self.write(b"\n")
                self.drain()
                continue
            if not r.startswith("ok true 17 "):
                break
            assert self.now() < end, "still moving after %d ms" % ms
            time.sleep(0.02)
        self.wait(300)

    # ---- the monitor --------------------------------------------------------
    def monitor(self, command):
        if self.qmp is None:
            self.qmp = socket.socket(socket.AF_UNIX)
            self.qmp.settimeout(REPLY_S)
            self.qmp.connect(self.qmp_path)
            self.qmp_buf = b""
            self._qmp_reply()  # greeting
            self._qmp_send({"execute": "qmp_capabilities"})
        return self._qmp_send({"execute": "human-monitor-command",
                               "arguments": {"command-line": command}})

    def _qmp_send(self, obj):
        self.qmp.sendall(json.dumps(obj).encode() + b"\n")
        return self._qmp_reply()

    def _qmp_reply(self):
        while True:
            while b"\n" not in self.qmp_buf:
                self.qmp_buf += self.qmp.recv(4096)
            line, self.qmp_buf = self.qmp_buf.split(b"\n", 1)
            msg = json.loads(line)
            if "event" in msg:
                continue
            if "error" in msg:
                raise AssertionError("qmp: %s" % msg["error"])
            return msg.get("return", msg)

    def counted(self, requests):
        """board_cost once the board has counted that many requests: the
        reply leaves during the poll, the count follows right after it."""
        deadline = time.monotonic() + REPLY_S
        while True:
            c = self.costs()
            if c["requests"] >= requests:
                assert c["requests"] == requests, "counted %d requests, sent %d" % (
                    c["requests"], requests)
                return c
            assert time.monotonic() < deadline, "request not counted"
            time.sleep(0.001)

    def costs(self):
        out = self.monitor("xp /14wx 0x%x" % symbol(self.elf, "board_cost"))
        w = [int(x, 16) for x in re.findall(r"\b0x([0-9a-f]{8})\b", out)]
        # ticks, tick_last, tick_worst, (pad), tick_sum lo, hi, requests,
        # req_last, req_worst, plans, plan_worst, stream_last,
        # stream_worst, due_worst
        return {"ticks": w[0], "tick_last": w[1], "tick_worst": w[2],
                "tick_sum": w[4] | w[5] << 32, "requests": w[6], "req_last": w[7],
                "req_worst": w[8], "plans": w[9], "plan_worst": w[10], "stream_last": w[11],
                "stream_worst": w[12], "due_worst": w[13]}


_symbols = {}


def symbol(elf, name):
    if (elf, name) not in _symbols:
        out = subprocess.run(["arm-none-eabi-nm", elf], check=True, capture_output=True,
                             text=True).stdout
        m = re.search(r"^([0-9a-f]+) \w %s$" % re.escape(name), out, re.M)
        assert m, "%s not in %s" % (name, elf)
        _symbols[elf, name] = int(m.group(1), 16)
    return _symbols[elf, name]


def instructions(cycles):
    """Instructions the emulated core ran in that many 25 MHz cycles."""
    return cycles * 1000000000 // CPU_HZ >> ICOUNT_SHIFT


# ---- the checks -------------------------------------------------------------

def expect(b, line, reply):
    got = b.ex(line)
    assert got == reply, "%r: got %r, expected %r" % (line, got, reply)


def position(b):
    m = re.match(r"ok true (-?\d+\.\d{3}) (-?\d+\.\d{3}) (-?\d+\.\d{3})$", b.ex("getPosition"))
    assert m, "bad getPosition reply"
    return tuple(float(v) for v in m.groups())


def expect_pos(b, x, y, th, tol_mm=COUNT_MM, tol_deg=0.01):
    """The reference wheel resolves one count (0.029 mm): within one count,
    as tests/test_conformance.c checks it for this wheel."""
    p = position(b)
    assert abs(p[0] - x) <= tol_mm and abs(p[1] - y) <= tol_mm and abs(p[2] - th) <= tol_deg, \
        "position %r, expected (%g, %g, %g)" % (p, x, y, th)
    return p


def ready(b):
    expect(b, "setPower true", "ok true")
    expect(b, "setServo true", "ok true")
    expect(b, "getState", 'ok true 16 "Ready"')


def queue_three(b):
    expect(b, "moveLinearAbs 300 0 0", "ok true")
    expect(b, "moveLinearAbs 600 0 0", "ok true")
    expect(b, "moveLinearAbs 900 0 0", "ok true")


def reset(b):
    """Back to the boot state between cases (the simulator boots afresh)."""
    b.ex("stop")
    b.settle(3000)
    b.ex("setPower false")
    expect(b, "clearAlarm", "ok true")
    expect(b, "setPosition 0 0 0", "ok true")
    expect(b, "setVelocity 500 90", "ok true")
    expect(b, "setAcceleration 500 180", "ok true")
    expect(b, "setJogTimeout 500", "ok true")
    expect(b, "setDigitalSensorLock off", "ok true")
    expect(b, "$jerk 0 0", "ok jerk 0.000 0.000 limit 0.000 0.000")
    expect(b, "getState", 'ok true 25 "Unpowered"')
    expect(b, "getActiveAlarm 1", "ok true 0 0")


def c_boot_and_queries(b):
    expect(b, "getState", 'ok true 25 "Unpowered"')
    expect(b, "getServoStatus 0", "ok true false")
    expect(b, "getServoStatus 1", "ok true false")
    expect(b, "getIFVersion", 'ok true "RTC VehicleService interface: ver.2.0.0"')
    expect(b, "getVersion", 'ok true "Ver.1.0.0"')
    expect(b, "getVelocityLimit", "ok true 1000.000 180.000")
    expect(b, "getAccelerationLimit", "ok true 1000.000 360.000")
    expect(b, "getDefaultVelocity", "ok true 500.000 90.000")
    expect(b, "getDefaultAcceleration", "ok true 500.000 180.000")
    expect(b, "getPosition", "ok true 0.000 0.000 0.000")
    expect(b, "getActiveAlarm 16", "ok true 0 0")
    # the compiled-in configuration (hal/cortexm/board_main.c), the store
    # erased (a fresh board): $config reads it; the help lines are left out
    expect(b, "$config tick_hz", "ok tick_hz 1000")
    expect(b, "$config store", "ok store empty table 0x916B11C3")
    expect(b, "$help moveForward", "ok 17 boolean moveForward(in double x_)")
    expect(b, "$help moveCircularRel",
           "ok 14 boolean moveCircularRel(in Point centerPoint, in double theta)")
    # the jerk it runs with, read and set ($jerk), and its limits (none)
    expect(b, "$jerk", "ok jerk 0.000 0.000 limit 0.000 0.000")
    expect(b, "$jerk 2000 1000", "ok jerk 2000.000 1000.000 limit 0.000 0.000")
    expect(b, "$jerk -1 0", "error 8 $jerk: -1 0 exceeds the limits or is below what the "
           "tick rate holds")
    expect(b, "$jerk 0 0", "ok jerk 0.000 0.000 limit 0.000 0.000")
    # the loopback battery: a constant 24.0 V, in 0.1 V units
    expect(b, "getBatteryVoltage", "ok true 240.000")
    expect(b, "moveForward 100", "ok false")
    expect(b, "getActiveAlarm 1", 'ok true 1 1 121 warning "moveForward refused: servo off"')
    expect(b, "getState", 'ok true 25 "Unpowered"')
    expect(b, "clearAlarm", "ok true")
    expect(b, "getActiveAlarm 1", "ok true 0 0")


def c_set_servo_table8(b):
    # up to the drive fault, which the loopback drives cannot raise
    expect(b, "setServo true", "ok false")
    expect(b, "getServoStatus 0", "ok true false")
    expect(b, "setServo false", "ok false")
    expect(b, "getServoStatus 1", "ok true false")
    expect(b, "getActiveAlarm 2", 'ok true 1 1 128 warning "setServo refused: power off"')
    expect(b, "clearAlarm", "ok true")
    expect(b, "setPower true", "ok true")
    expect(b, "getState", 'ok true 24 "Powered"')
    expect(b, "setServo false", "ok true")
    expect(b, "getState", 'ok true 24 "Powered"')
    expect(b, "setServo true", "ok true")
    expect(b, "getServoStatus 0", "ok true true")
    expect(b, "getServoStatus 1", "ok true true")
    expect(b, "getServoStatus 2", "ok false false")
    expect(b, "clearAlarm", "ok true")
    expect(b, "getState", 'ok true 16 "Ready"')
    expect(b, "setServo true", "ok true")
    expect(b, "getState", 'ok true 16 "Ready"')
    expect(b, "setServo false", "ok true")
    expect(b, "getServoStatus 0", "ok true false")
    expect(b, "getState", 'ok true 24 "Powered"')


def c_state_strings(b):
    # up to the relay failure, which the loopback relay cannot raise
    expect(b, "getState", 'ok true 25 "Unpowered"')
    expect(b, "setPower on", "ok true")
    expect(b, "getState", 'ok true 24 "Powered"')
    expect(b, "setServo on", "ok true")
    expect(b, "getState", 'ok true 16 "Ready"')
    # slowly (5 s of the unit's time), so that the harness, delayed on a
    # busy host while the emulated clock runs on, still finds it Busy
    expect(b, "setVelocity 100 90", "ok true")
    expect(b, "moveForward 500", "ok true")
    expect(b, "getState", 'ok true 17 "Busy"')
    expect(b, "moveTurn 90", "ok false")
    expect(b, "getActiveAlarm 5", 'ok true 1 1 120 warning "moveTurn refused: unit not ready"')
    expect(b, "getState", 'ok true 17 "Busy"')
    b.settle(8000)
    expect_pos(b, 500, 0, 0)
    expect(b, "setVelocity 500 90", "ok true")
    expect(b, "getState", 'ok true 18 "Warning-120"')
    expect(b, "moveForward -500", "ok true")
    b.settle(4000)
    expect_pos(b, 0, 0, 0)
    expect(b, "clearAlarm", "ok true")
    expect(b, "getState", 'ok true 16 "Ready"')
    expect(b, "pause", "ok true")
    expect(b, "getState", 'ok true 21 "Paused"')
    expect(b, "resume", "ok true")
    expect(b, "getState", 'ok true 16 "Ready"')
    expect(b, "setPower off", "ok true")
    expect(b, "getState", 'ok true 25 "Unpowered"')


def c_active_alarm_count(b):
    expect(b, "setServo on", "ok false")
    expect(b, "setOutput 0 1 1", "ok false")
    expect(b, "getServoStatus 9", "ok false false")
    expect(b, "getActiveAlarm 0", "ok true 3 0")
    expect(b, "getActiveAlarm -1", "ok true 3 0")
    expect(b, "getActiveAlarm 1",
           'ok true 3 1 127 warning "getServoStatus refused: no such axis"')
    expect(b, "getActiveAlarm 2",
           'ok true 3 2 127 warning "getServoStatus refused: no such axis" '
           '126 warning "setOutput refused: io id 0 reserved"')
    expect(b, "getActiveAlarm 32767",
           'ok true 3 3 127 warning "getServoStatus refused: no such axis" 126 warning '
           '"setOutput refused: io id 0 reserved" 128 warning "setServo refused: power off"')
    expect(b, "getActiveAlarm 0", "ok true 3 0")
    expect(b, "clearAlarm", "ok true")
    expect(b, "getActiveAlarm 32767", "ok true 0 0")


def c_io(b):
    # the refusals; the board has no IO module, so no id is served
    expect(b, "setOutput 0 1 1", "ok false")
    expect(b, "getActiveAlarm 1", 'ok true 1 1 126 warning "setOutput refused: io id 0 reserved"')
    expect(b, "getInput 0", "ok false 0")
    expect(b, "setOutput 99 1 1", "ok false")
    expect(b, "setOutput 1 1 1", "ok false")
    expect(b, "getInput 99", "ok false 0")
    expect(b, "getInput 3", "ok false 0")
    expect(b, "clearAlarm", "ok true")


def c_move_forward_position(b):
    ready(b)
    expect(b, "moveForward 1000", "ok true")
    expect(b, "getState", 'ok true 17 "Busy"')
    b.settle(5000)
    expect(b, "getState", 'ok true 16 "Ready"')
    expect_pos(b, 1000, 0, 0)
    expect(b, "setPosition 0 0 0", "ok true")
    expect(b, "moveLinearRel 200 0 0", "ok true")
    b.settle(3000)
    expect_pos(b, 200, 0, 0)


def at_once(b, *lines):
    """Sends the lines in one write, so the board runs them within a few of
    its ticks whatever the host's scheduling; returns their replies."""
    b.write(b"".join(l.encode() + b"\n" for l in lines))
    return [b.readline() for _ in lines]


def moving_then(b, line):
    """Once the unit has moved 20 mm, runs line between two getPositions
    (one write); returns the positions before and after. The unit was
    between the two when line ran, however the host's writes reach the
    board."""
    end = b.now() + 3000
    while position(b)[0] < 20:
        assert b.now() < end, "not moving"
    p0, r, p1 = at_once(b, "getPosition", line, "getPosition")
    assert r == "ok true", "%s: %r" % (line, r)
    at = []
    for p in (p0, p1):
        m = re.match(r"ok true (-?\d+\.\d{3}) ", p)
        assert m, p
        at.append(float(m.group(1)))
    return at


# The reference leads the odometry getPosition reads by at most one tick of
# travel: 0.5 mm at the default 500 mm/s.
TICK_LEAD_MM = 0.5


def braked_within(x, at):
    """Where a unit that was between at[0] and at[1] when it was told to
    brake stops: it accelerated from rest at the default 500 mm/s^2, so
    braking at the same rate takes no longer than getting there did, and no
    more than from the default 500 mm/s (250 mm)."""
    top = at[1] + TICK_LEAD_MM
    return at[0] - COUNT_MM <= x <= top + min(top, 500.0 ** 2 / (2 * 500.0)) + COUNT_MM


def c_pause_resume_keeps_queue(b):
    ready(b)
    queue_three(b)
    at = moving_then(b, "pause")
    b.wait(1500)
    expect(b, "getState", 'ok true 21 "Paused"')
    x = position(b)[0]
    assert braked_within(x, at) and x < 900, "paused at %g from %s" % (x, at)
    b.wait(1000)
    assert abs(position(b)[0] - x) < 0.05, "moved while paused"
    expect(b, "moveLinearAbs 1000 0 0", "ok true")
    expect(b, "getState", 'ok true 21 "Paused"')
    expect(b, "resume", "ok true")
    expect(b, "getState", 'ok true 17 "Busy"')
    b.settle(15000)
    expect(b, "getState", 'ok true 16 "Ready"')
    expect_pos(b, 1000, 0, 0)
    expect(b, "getActiveAlarm 1", "ok true 0 0")


def c_pause_idle_then_queue(b):
    ready(b)
    expect(b, "pause", "ok true")
    expect(b, "getState", 'ok true 21 "Paused"')
    expect(b, "moveLinearAbs 400 0 0", "ok true")
    b.wait(1000)
    expect(b, "getPosition", "ok true 0.000 0.000 0.000")
    expect(b, "resume", "ok true")
    b.settle(4000)
    expect_pos(b, 400, 0, 0)
    expect(b, "getState", 'ok true 16 "Ready"')


def c_stop_discards(b):
    ready(b)
    queue_three(b)
    at = moving_then(b, "stop")
    b.settle(2000)
    expect(b, "getState", 'ok true 16 "Ready"')
    x = position(b)[0]
    assert braked_within(x, at) and x < 900, "stopped at %g from %s" % (x, at)
    before = position(b)
    expect(b, "resume", "ok true")
    b.wait(1000)
    # at rest the wheel loop may settle by one encoder count, never along the path
    expect_pos(b, *before)
    d = b.ex("$diag")
    assert d.startswith("ok ticks") and " mode idle queue 0 " in d, d


BAD_LINES = [
    b"moveForward", b"moveLinearAbs 1 2", b"moveLinearAbs nan 0 0", b"moveLinearAbs 1e999 0 0",
    b"moveLinearAbs 0x10 0 0", b"stopp", b"STOP now", b"pause 1", b"setPower maybe",
    b"setServo 2", b"getInput -1", b"setOutput 3 1 4294967296", b"getActiveAlarm 40000",
    b"stop\x01", b"$nope",
]


def c_bad_lines_keep_queue(b):
    ready(b)
    # Three moves of 1 m (the simulator's test: 300 mm): while a loaded host
    # is slow to send the bad lines, the unit's time runs on, and the queue
    # must outlast them for "Busy" to hold.
    for x in (1000, 2000, 3000):
        expect(b, "moveLinearAbs %d 0 0" % x, "ok true")
    for line in BAD_LINES:
        r = b.ex(line)
        assert r.startswith("error "), "%r: %r" % (line, r)
        b.wait(10)
    expect(b, b"stop" + b" " * 295, "error 6 line too long (max 255 bytes)")
    expect(b, "getActiveAlarm 1", "ok true 0 0")
    expect(b, "getState", 'ok true 17 "Busy"')
    b.settle(20000)
    expect_pos(b, 3000, 0, 0)
    expect(b, "getState", 'ok true 16 "Ready"')
    at_rest = position(b)
    for line in BAD_LINES:
        r = b.ex(line)
        assert r.startswith("error "), "%r: %r" % (line, r)
    b.wait(500)
    expect_pos(b, *at_rest)  # the wheel loop may settle by one count
    expect(b, "getState", 'ok true 16 "Ready"')


def c_serial_stream(b):
    # the simulator's script, with its "$wait 8000" done by the harness
    b.write(b"# bring-up\r\nsetPower on\r\nsetServo on\r\n\r\nmoveLinearAbs 300 0 0\r\n"
            b"moveLinearAbs 600 0 0\r\n\x01\x02\xff garbage\r\nmoveLinearAbs 600\r\n")
    got = [b.readline() for _ in range(6)]
    assert got == ["ok true", "ok true", "ok true", "ok true", "error 7 binary data in line",
                   "error 2 moveLinearAbs takes 3 arguments, got 1"], got
    b.settle(8000)
    b.write(b"getPosition\r\ngetState\n")
    p = b.readline()
    assert re.match(r"ok true 600\.0\d\d 0\.000 0\.000$|ok true 599\.9[789]\d 0\.000 0\.000$",
                    p), p
    assert b.readline() == 'ok true 16 "Ready"'


def c_settings(b):
    expect(b, "setVelocity 0 10", "ok false")
    expect(b, "setVelocity 100 -1", "ok false")
    expect(b, "setVelocity 1000.001 10", "ok false")
    expect(b, "setVelocity 1000 180", "ok true")
    expect(b, "getActiveAlarm 2", 'ok true 1 1 111 warning "setVelocity refused: out of limits"')
    expect(b, "setAcceleration 0 10", "ok false")
    expect(b, "setAcceleration 100 361", "ok false")
    expect(b, "setAcceleration 1000 360", "ok true")
    expect(b, "setJogTimeout 0", "ok false")
    expect(b, "setJogTimeout -5", "ok false")
    expect(b, "setJogTimeout 200", "ok true")
    expect(b, "setJoystick on", "ok true")
    expect(b, "setJoystick off", "ok true")
    expect(b, "setPosition 100 -50 30", "ok true")
    expect(b, "getPosition", "ok true 100.000 -50.000 30.000")
    expect(b, "setPosition 0 0 190", "ok true")
    expect(b, "getPosition", "ok true 0.000 0.000 -170.000")
    expect(b, "clearAlarm", "ok true")
    expect(b, "setPosition 0 0 0", "ok true")
    ready(b)
    expect(b, "moveForward 1000", "ok true")
    b.wait(200)
    expect(b, "setAcceleration 500 180", "ok false")
    expect(b, "setVelocity 200 90", "ok true")
    expect(b, "getActiveAlarm 1",
           'ok true 1 1 122 warning "setAcceleration refused: unit moving"')
    b.settle(8000)
    expect_pos(b, 1000, 0, 0)


def c_other_moves(b):
    ready(b)
    expect(b, "moveJog 0 100 0", "ok false")
    expect(b, "getActiveAlarm 1",
           'ok true 1 1 112 warning "moveJog refused: not possible on this base"')
    expect(b, "moveCircularRel 100 500 90", "ok false")
    expect(b, "moveJog 1000.5 0 0", "ok false")
    expect(b, "moveJog 0 0 -180.5", "ok false")
    expect(b, "clearAlarm", "ok true")
    expect(b, "setJogTimeout 100", "ok true")
    # in one write: the jog lasts 200 ms of the unit's time
    b.write(b"moveJog -200 0 0\ngetState\n")
    got = [b.readline(), b.readline()]
    assert got == ["ok true", 'ok true 17 "Busy"'], got
    b.settle(2000)
    expect(b, "getState", 'ok true 16 "Ready"')
    # 100 ms accelerating at 500 mm/s^2, then the same braking: 2.5 + 2.5 mm
    # (the watchdog counts from the request's arrival: within one tick)
    expect_pos(b, -5, 0, 0, tol_mm=0.3)
    expect(b, "moveJog 0 0 0", "ok true")
    b.settle(1000)
    expect(b, "setPosition 0 0 0", "ok true")
    expect(b, "moveTurn 90", "ok true")
    b.settle(3000)
    x, y, th = position(b)
    assert 89.99 < th < 90.01 and abs(x) < COUNT_MM and abs(y) < COUNT_MM, (x, y, th)
    expect(b, "setPosition 0 0 0", "ok true")
    expect(b, "moveCircularRel 0 500 90", "ok true")
    b.settle(6000)
    expect(b, "getState", 'ok true 16 "Ready"')
    x, y, th = position(b)
    assert 499 < x < 501 and 499 < y < 501 and 89.9 < th < 90.1, (x, y, th)
    expect(b, "setPosition 0 0 0", "ok true")
    expect(b, "moveContinuousRel 1000 0 0", "ok true")
    at = moving_then(b, "moveContinuousRel 100 0 0")
    b.settle(4000)
    x = position(b)[0]
    # the new goal is 100 mm from the reference when the request ran:
    # between the two getPositions around it, plus the reference's lead
    assert at[0] + 100 - COUNT_MM <= x <= at[1] + 100 + TICK_LEAD_MM + COUNT_MM, (x, at)
    expect(b, "getState", 'ok true 16 "Ready"')
    expect(b, "setPosition 0 0 0", "ok true")
    expect(b, "moveCruiseAbs 300 0", "ok true")
    expect(b, "moveCruiseAbs 600 0", "ok true")
    b.settle(6000)
    expect(b, "getState", 'ok true 16 "Ready"')
    x = position(b)[0]
    assert 599.9 < x < 600.1, x


def c_link_watchdog(b):
    """The link watchdog on the board: 1 s of silence mid-route stops it
    (warning 153) and discards the queue."""
    expect(b, "$watchdog 1000", "ok watchdog 1000")
    ready(b)
    expect(b, "moveForward 3000", "ok true")
    expect(b, "moveLinearAbs 0 0 0", "ok true")
    b.wait(3000)
    expect(b, "getActiveAlarm 1", 'ok true 1 1 153 warning "link lost: console silent 1000 ms"')
    expect(b, "getState", 'ok true 18 "Warning-153"')
    assert re.search(r" mode idle queue 0 ", b.ex("$diag")), "queue kept"
    expect(b, "$watchdog 0", "ok watchdog 0")


CONFORMANCE = [c_boot_and_queries, c_set_servo_table8, c_state_strings, c_active_alarm_count,
               c_io, c_move_forward_position, c_pause_resume_keeps_queue,
               c_pause_idle_then_queue, c_stop_discards, c_bad_lines_keep_queue,
               c_serial_stream, c_settings, c_other_moves]


# ---- what a request costs on the board ---------------------------------------

# Every operation and bring-up extra once, in a sequence that also reaches the
# expensive cases: a full queue of blended waypoints, a retarget while moving,
# the alarm list with every warning a refusal can raise.
REQUESTS = [
    "getState", "getVersion", "getIFVersion", "getVelocityLimit", "getAccelerationLimit",
    "getDefaultVelocity", "getDefaultAcceleration", "getBatteryVoltage", "getPosition",
    "getServoStatus 0", "getInput 1", "setOutput 1 1 1", "setJoystick off",
    "setDigitalSensorLock off", "setJogTimeout 500", "setVelocity 500 90",
    "setAcceleration 500 180", "setPosition 0 0 0", "setPower true", "setServo true",
    "moveForward 100", "stop", "moveTurn 10", "stop", "moveLinearRel 10 0 0", "stop",
    "moveLinearAbs 0 0 0", "stop", "moveCircularRel 0 500 10", "stop",
    "moveJog 100 0 10", "moveJog 0 0 0", "stop",
] + ["moveCruiseAbs %d %d" % (1000 * (k + 1), 300 * (k % 3)) for k in range(16)] + [
    "moveCruiseAbs 99999 0", "pause", "resume", "stop",
    "moveContinuousRel 3000 0 0", "moveContinuousRel 1500 400 20",
    "moveContinuousRel 1500 -400 -20", "stop", "unlock", "clearAlarm", "setServo true",
    # one refusal of each kind the board can raise: 12 warnings in the list
    "moveJog 0 100 0", "setVelocity 0 10", "moveLinearRel 1e12 0 0", "setOutput 0 1 1",
    # (a move long enough that no host delay lets it end before the
    # refusals that need it running: 100 m at 500 mm/s)
    "getServoStatus 9", "moveForward 100000", "moveTurn 10", "setAcceleration 400 180",
    "pause", "moveJog 100 0 0",
] + ["moveLinearAbs %d 0 0" % (100 * k) for k in range(17)] + [
    "stop", "setJoystick on", "moveForward 10", "setJoystick off", "setServo false",
    "moveForward 10", "setPower false", "setServo true",
    "getActiveAlarm 32767", "clearAlarm", "$help", "$help moveContinuousRel", "$version",
    "$diag", "$link", "$jerk", "$jerk 0 0",
]


# Replies these requests must give (the rest: any "ok" reply).
MUST_RUN = {"moveContinuousRel 3000 0 0", "moveContinuousRel 1500 400 20",
            "moveContinuousRel 1500 -400 -20", "getActiveAlarm 32767"}
# Before these, the unit is let come to rest: the stop before may still brake.
FROM_REST = {"moveForward 100000", "moveContinuousRel 3000 0 0"}


def request_cost(b, line):
    before = b.costs()["requests"]
    reply = b.ex(line)
    return reply, b.counted(before + 1)["req_last"]


def c_request_costs(b):
    worst = (0, "")
    for line in REQUESTS:
        if line in FROM_REST:
            b.settle(10000)
        reply, cyc = request_cost(b, line)
        assert reply.startswith("ok"), "%r: %r" % (line, reply)
        if line in MUST_RUN:
            assert reply.startswith("ok true"), "%r: %r" % (line, reply)
        if os.environ.get("MCU_COSTS"):
            print("  %6d cycles %6d instructions  %s -> %s" % (cyc, instructions(cyc), line,
                                                              reply[:50]))
        worst = max(worst, (cyc, line))
        if line == "getActiveAlarm 32767":
            n = int(reply.split()[2])
            assert n >= 12, "only %d alarms: %s" % (n, reply)
        if line.startswith("move"):
            b.wait(2)
    cyc, line = worst
    print("  worst request: %r, %d cycles = %d instructions, %.0f %% of a 1 ms period "
          "at 25 MHz" % (line, cyc, instructions(cyc), 100.0 * cyc / PERIOD_CYCLES))
    assert cyc < PERIOD_CYCLES, "%r takes %d cycles, over a period" % (line, cyc)
    assert b.ticks()[1] == 0, "tick overruns"


# Routes whose corner speeds all follow the braking distance to the last
# waypoint (1000 mm/s, 200 mm/s^2), so that each waypoint queued raises every
# corner before it, then a new speed on the full queue: the corner planning
# a request runs is bounded (the board's PLAN_BUDGET) and its idle passes do
# the rest. Each route must still end exactly on its last waypoint.
ROUTES = {
    "straight, 30 mm apart": [(30 * (k + 1), 0) for k in range(17)],
    "a 2 m circle, 20 mm apart": [(2000 * math.sin((k + 1) * 0.01),
                                   2000 - 2000 * math.cos((k + 1) * 0.01)) for k in range(17)],
}


def c_planning_costs(b):
    ready(b)
    expect(b, "setVelocity 1000 90", "ok true")
    expect(b, "setAcceleration 200 180", "ok true")
    worst = (0, "")
    for name, route in ROUTES.items():
        expect(b, "setPosition 0 0 0", "ok true")
        last = None
        for x, y in route:
            reply, cyc = request_cost(b, "moveCruiseAbs %.3f %.3f" % (x, y))
            assert reply in ("ok true", "ok false"), reply
            if reply == "ok true":
                last = (x, y)
            else:  # the queue is full: the refusal is a warning
                expect(b, "clearAlarm", "ok true")
            worst = max(worst, (cyc, "%s: moveCruiseAbs" % name))
        reply, cyc = request_cost(b, "setVelocity 800 60")
        assert reply == "ok true", reply
        worst = max(worst, (cyc, "%s: setVelocity on the queue" % name))
        t0 = b.now()
        b.settle(120000)
        if os.environ.get("MCU_COSTS"):
            print("  %s: %d ms" % (name, b.now() - t0))
        p = position(b)
        assert abs(p[0] - round(last[0], 3)) <= COUNT_MM and abs(p[1] - round(last[1], 3)) <= COUNT_MM, \
            "%s: ended at %r, not on %r" % (name, p, last)
        expect(b, "setVelocity 1000 90", "ok true")
    c = b.costs()
    cyc, what = worst
    print("  worst planning request: %s, %d cycles = %d instructions, %.0f %% of a 1 ms period "
          "at 25 MHz; idle planning: %d calls, worst %d instructions"
          % (what, cyc, instructions(cyc), 100.0 * cyc / PERIOD_CYCLES, c["plans"],
             instructions(c["plan_worst"])))
    assert cyc < PERIOD_CYCLES, "%s takes %d cycles, over a period" % (what, cyc)
    assert c["plans"] > 0 and c["plan_worst"] < PERIOD_CYCLES // 4, c
    assert b.ticks()[1] == 0, "tick overruns"
    expect(b, "getActiveAlarm 1", "ok true 0 0")


def c_version_burst(b):
    # 50 lines in one write: before the table checksum was kept, each cost
    # 38,000 instructions and the burst raised fault 209.
    c0 = b.costs()
    assert c0["req_worst"] < PERIOD_CYCLES, "a request before took %d cycles" % c0["req_worst"]
    b.write(b"$version\n" * 50)
    for _ in range(50):
        r = b.readline()
        assert r.startswith('ok firmware "Ver.1.0.0"') and r.endswith("protocol 1 table 0x1F09"), r
    c = b.counted(c0["requests"] + 50)
    assert c["req_worst"] < PERIOD_CYCLES, "a $version took %d cycles" % c["req_worst"]
    expect(b, "getActiveAlarm 1", "ok true 0 0")
    assert b.ticks()[1] == 0, "tick overruns"
    print("  $version: %d cycles = %d instructions" % (c["req_last"], instructions(c["req_last"])))


def vctl(b, vehiclectl, *args):
    r = subprocess.run([vehiclectl, "--port", b.pty, "--timeout", "5000"] + list(args),
                       capture_output=True,
                       text=True, timeout=REPLY_S)
    return r.returncode, r.stdout.strip()


def c_vehiclectl_frames(b, vehiclectl):
    link0 = b.ex("$link")
    frames0 = int(re.search(r"frames (\d+)", link0).group(1))
    rc, out = vctl(b, vehiclectl, "info")
    assert rc == 0 and out == "protocol 1 table 0x1F09 operations 34 (matches this vehiclectl)", out
    info_cost = b.costs()["req_last"]
    print("  protocol info frame: %d cycles = %d instructions" % (info_cost, instructions(info_cost)))
    assert info_cost < PERIOD_CYCLES // 4, "protocol info: %d cycles" % info_cost
    assert vctl(b, vehiclectl, "getState") == (0, 'true state=25 Msg="Unpowered"')
    assert vctl(b, vehiclectl, "setPower", "true") == (0, "true")
    assert vctl(b, vehiclectl, "setServo", "on") == (0, "true")
    assert vctl(b, vehiclectl, "moveForward", "500") == (0, "true")
    assert vctl(b, vehiclectl, "moveTurn", "90") == (1, "false")
    rc, out = vctl(b, vehiclectl, "--json", "getActiveAlarm", "1")
    assert rc == 0 and json.loads(out)["numOfActiveAlarm"] == 1, out
    # a frame a stalled host delivered late leaves bytes in the console
    b.write(b"\n")
    b.drain()
    b.settle(4000)
    rc, out = vctl(b, vehiclectl, "--json", "getPosition")
    p = json.loads(out)
    assert rc == 0 and abs(p["x"] - 500) <= COUNT_MM and abs(p["y"]) <= COUNT_MM and \
        abs(p["theta"]) <= 0.01, out
    assert vctl(b, vehiclectl, "clearAlarm") == (0, "true")
    rc, out = vctl(b, vehiclectl, "--json", "watch", "--count", "2", "--interval", "50")
    assert rc == 0 and len(out.splitlines()) == 2, out
    # All of it went as binary frames. A frame QEMU hands over more than
    # 100 ms of the unit's time late (a stalled host) is dropped as truncated
    # and vehiclectl sends it again; its bytes then reach the console, which
    # a newline clears.
    b.write(b"\n")
    b.drain()
    link1 = b.ex("$link")
    m = re.match(r"ok frames (\d+) executed (\d+) duplicates \d+ naks \d+ crc 0 oversize 0 "
                 r"truncated \d+ other \d+ txdrop 0$", link1)
    assert m and int(m.group(1)) - frames0 >= 10, link1
    reset(b)


def c_bbox(b, vehiclectl):
    """The black box on the board (docs/mcu.md): 8 samples, one every 250
    ticks; status and clear on the console, the samples in frames; empty
    after a clear, then one sample per 250 ms of the unit's time."""
    t_clear_lo = b.now()
    expect(b, "$bbox clear", "ok bbox armed")
    t_clear_hi = b.now()
    expect(b, "$bbox", "ok bbox armed samples 0 of 8 every 250 tick_hz 1000 trigger 0 fault 0")
    expect(b, "$bbox dump 0", "error 8 $bbox dump is not in this build: read it in frames")
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "bbox.csv")
        assert vctl(b, vehiclectl, "bbox", path) == (
            0, "bbox armed: 0 samples, one every 250 ticks at 1000 Hz, fault 0 at tick 0")
        with open(path) as f:
            head = f.readline().strip()
            assert head.startswith("time_s,cmd_x_mm,") and head.endswith(",tick,fault"), head
            assert f.read() == ""
        b.wait(1100)
        # One sample each 250 of the unit's ticks since the clear: as many
        # as the unit's time between the clear and the read holds (read
        # through the monitor around it), however late a loaded host runs
        # vehiclectl (4 or 5 on an idle one).
        t_read_lo = b.now()
        rc, out = vctl(b, vehiclectl, "bbox", path)
        t_read_hi = b.now()
        m = re.match(r"bbox armed: (\d+) samples, one every 250 ticks at 1000 Hz, "
                     r"fault 0 at tick 0$", out)
        assert rc == 0 and m, out
        least = (t_read_lo - t_clear_hi - 1) // 250
        most = min(8, (t_read_hi - t_clear_lo + 1) // 250)
        assert 4 <= least <= int(m.group(1)) <= most, (out, least, most)
        with open(path) as f:
            rows = list(csv.DictReader(f))
        ticks = [int(r["tick"]) for r in rows]
        assert len(rows) == int(m.group(1)), rows
        assert all(b2 - a == 250 for a, b2 in zip(ticks, ticks[1:])), ticks
        assert all(r["state"] == "25" and r["fault"] == "0" for r in rows), rows
        b.wait(2000)
        rc, out = vctl(b, vehiclectl, "bbox", path)
        assert rc == 0 and out.startswith("bbox armed: 8 samples,"), out
    b.write(b"\n")
    b.drain()


class PtyPort:
    """The board's pty as the pyserial port vehicleservice's FrameTransport
    reads and writes."""

    def __init__(self, b):
        self.b = b
        self.timeout = 0.05
        self.in_waiting = 0

    def write(self, data):
        self.b.write(data)

    def flush(self):
        pass

    def read(self, n):
        if select.select([self.b.fd], [], [], self.timeout)[0]:
            return os.read(self.b.fd, 4096)
        return b""


def frames_client(b):
    assert b.drain() == b"", "bytes before the frames"
    return Vehicle(FrameTransport(PtyPort(b), timeout=5.0))


def subscribe(v, mask, period_ms):
    """The subscription's answer: mask, period, frame bytes, fastest
    period, tick rate. The frames kept while waiting for it were the
    stream before it: dropped."""
    r = struct.unpack("<5H", v.transport.exchange(vs_stream.OP_STREAM,
                                                  struct.pack("<HH", mask, period_ms)))
    v.transport._stream.clear()
    return r


def next_frames(v, n):
    """The next n stream frames as (seq, mask, tick, {row: integer})."""
    out = []
    for _ in range(n):
        seq, payload = v.transport.next_stream(REPLY_S)
        out.append((seq,) + vs_stream.decode(payload))
    return out


def consecutive(frames, period):
    """Sequence numbers one apart, tick stamps exactly period ticks apart:
    no frame skipped."""
    for a, b2 in zip(frames, frames[1:]):
        assert b2[0] == (a[0] + 1) & 0xFF and b2[2] - a[2] == period, \
            "frames %r then %r" % (a[:3], b2[:3])


# docs/protocol.md's budget at the board's line (115,207 baud: 25 MHz / 217):
# pose+state, 28 bytes a frame, every 4 ms at the fastest; every group, 52
# bytes, every 7 ms; $stream's text line of every group, 370 bytes at most,
# every 43 ms.
AT_REST = {"x_dmm": 1003, "y_dmm": -505, "theta_mdeg": 30000, "state": 25, "alarms": 0}


def c_telemetry_stream(b):
    """The telemetry stream in frames (docs/protocol.md): pose and state
    every 10 ms at rest, 20 frames one tick count period apart holding
    exactly what getPosition and getState read; requests between the
    frames all answered, none skipped; a rate the line cannot carry NAKed
    (8) and the stream in force kept; none after the unsubscription; and
    the stream is no request: the link watchdog stops a move it watches."""
    expect(b, "setPosition 100.25 -50.5 30", "ok true")
    expect(b, "getPosition", "ok true 100.250 -50.500 30.000")
    expect(b, "getState", 'ok true 25 "Unpowered"')
    v = frames_client(b)
    n0 = b.costs()["requests"]
    assert subscribe(v, 0x09, 10) == (0x09, 10, 28, 4, 1000)
    run = next_frames(v, 20)
    assert run[0][0] == 0, "first frame seq %d" % run[0][0]
    consecutive(run, 10)
    for seq, mask, tick, vals in run:
        assert mask == 0x09 and vals == AT_REST, (seq, mask, tick, vals)
    # frames are no requests: only the subscription was counted
    assert b.counted(n0 + 1)["requests"] == n0 + 1
    for _ in range(20):
        assert v.call("getState") == [True, 25, "Unpowered"]
        assert v.call("getPosition") == [True, 100.25, -50.5, 30.0]
    more = next_frames(v, 5)
    run += more
    consecutive(run, 10)
    st = v.console_line("$stream")
    m = re.match(r"stream mask 0x09 period 10 sent (\d+) skipped 0$", st)
    assert m and int(m.group(1)) >= len(run), st
    # every group every 6 ms: over the line's 3/4; the stream goes on
    try:
        subscribe(v, 0xFF, 6)
        raise AssertionError("every group at 6 ms taken")
    except NakError as e:
        assert e.status == 8, e
    consecutive(run + next_frames(v, 3), 10)
    assert subscribe(v, 0xFF, 7) == (0xFF, 7, 52, 7, 1000)
    seq, mask, _, vals = next_frames(v, 1)[0]
    assert mask == 0xFF and seq == 0 and vals["battery_cV"] == 2400 and vals["queue"] == 0, vals
    assert subscribe(v, 0, 0) == (0, 0, 0, 0, 1000)
    b.wait(100)
    assert not v.transport._buf and b.drain() == b"", "a frame after the unsubscription"
    # The link watchdog (1 s) on a move while only frames flow: warning 153.
    assert v.console_line("$watchdog 1000") == "watchdog 1000"
    assert subscribe(v, 0x19, 100) == (0x19, 100, 33, 4, 1000)
    for name, args in (("setPower", (True,)), ("setServo", (True,)),
                       ("moveForward", (3000.0,))):
        assert v.call(name, *args)[0], name
    # Busy, the warning raised while it brakes, then Warning-153 at rest
    states = []
    for _ in range(60):
        seq, _, _, vals = next_frames(v, 1)[0]
        states.append((vals["state"], vals["alarm_code"]))
        if vals["state"] == 18:
            break
    codes = [code for _, code in states if code]
    assert (17, 0) in states and states[-1] == (18, 153) and set(codes) == {153}, states
    assert subscribe(v, 0, 0) == (0, 0, 0, 0, 1000)
    assert v.console_line("$watchdog 0") == "watchdog 0"
    b.wait(100)
    assert b.drain() == b""
    c = b.costs()
    print("  a stream frame: last %d cycles, worst %d (%d instructions); a tick with its "
          "frame: worst %d cycles, %.1f %% of a 1 ms period at 25 MHz"
          % (c["stream_last"], c["stream_worst"], instructions(c["stream_worst"]),
             c["due_worst"], 100.0 * c["due_worst"] / PERIOD_CYCLES))


def c_stream_text(b):
    """$stream, the text form on the console: ~stream lines between the
    replies, one period of ticks apart; a rate the line cannot carry
    refused; none after $stream off."""
    expect(b, "$stream", "ok stream mask 0x00 period 0 sent 0 skipped 0")
    expect(b, "$stream all 42",
           "error 8 $stream: the line carries these every 43 ms at the fastest")
    expect(b, "$stream pose,speed 100", "error 8 $stream GROUPS PERIOD_MS: groups all, a mask "
           "or pose,cmd,meas,state,alarm,battery,io,queue")
    expect(b, "$stream pose,state 100", "ok stream mask 0x09 period 100 text")
    lines = [b.readline() for _ in range(5)]
    got = []
    for line in lines:
        m = re.match(r"~stream (\d+) (\d+) x_dmm 0 y_dmm 0 theta_mdeg 0 state 25 alarms 0$",
                     line)
        assert m, lines
        got.append((int(m.group(1)), int(m.group(2))))
    assert [s for s, _ in got] == [0, 1, 2, 3, 4], got
    assert all(t1 - t0 == 100 for (_, t0), (_, t1) in zip(got, got[1:])), got

    def reply(line):
        b.write(line.encode() + b"\n")
        while True:
            r = b.readline()
            if not r.startswith("~stream "):
                return r

    r = reply("$stream")
    assert re.match(r"ok stream mask 0x09 period 100 sent \d+ skipped 0 text$", r), r
    assert reply("getState") == 'ok true 25 "Unpowered"'
    assert reply("$stream off") == "ok stream off"
    b.wait(300)
    assert b.drain() == b"", "a line after $stream off"


def c_tick_cost(b):
    c = b.costs()
    mean = c["tick_sum"] / c["ticks"]
    print("  ticks so far: %d, mean %.0f cycles (%d instructions), worst %d cycles "
          "(%d instructions, %.1f %% of a 1 ms period at 25 MHz)"
          % (c["ticks"], mean, instructions(int(mean)), c["tick_worst"],
             instructions(c["tick_worst"]), 100.0 * c["tick_worst"] / PERIOD_CYCLES))
    assert c["ticks"] > 50000, "%d ticks" % c["ticks"]
    assert c["tick_worst"] < PERIOD_CYCLES // 2, "worst tick %d cycles" % c["tick_worst"]
    # every request of the cases so far fitted a period: none delayed a tick
    assert c["req_worst"] < PERIOD_CYCLES, "worst request %d cycles" % c["req_worst"]
    # The stream frame (or line) goes out after the tick, between ticks:
    # like a request, it may take no more than a period less the worst
    # tick, so that a tick and its frame never make the next tick late.
    print("  a tick with its stream frame: worst %d cycles (%d instructions); the frame "
          "alone: worst %d cycles, %.0f %% of a period"
          % (c["due_worst"], instructions(c["due_worst"]), c["stream_worst"],
             100.0 * c["stream_worst"] / PERIOD_CYCLES))
    assert 0 < c["stream_worst"] <= c["due_worst"] < PERIOD_CYCLES, c
    assert c["stream_worst"] + c["tick_worst"] < PERIOD_CYCLES, c
    assert b.ticks()[1] == 0, "tick overruns"


def c_tick_bench(bench_elf):
    """make bench's Cortex-M4 figures (tools/bench/mcu_tickcost.sh): every
    scenario runs, and the worst tick meets its target (below 10 % of the
    1 ms period at 168 MHz)."""
    here = os.path.dirname(os.path.abspath(__file__))
    r = subprocess.run([os.path.join(here, "..", "..", "tools", "bench", "mcu_tickcost.sh"),
                        bench_elf], capture_output=True, text=True, timeout=600)
    print("\n".join("  " + line for line in r.stdout.splitlines()))
    assert r.returncode == 0, r.stdout + r.stderr
    assert re.search(r"^  target: worst tick < 10 %.*\n.* -> met$", r.stdout, re.M), r.stdout


def c_div_check(elf):
    """The image's 64-bit division (hal/cortexm/udivmod64.c) on the board,
    against the bitwise one of tests/mcu/divcheck.c: exit status 0."""
    r = subprocess.run(["qemu-system-arm", "-M", "mps2-an386", "-nographic", "-monitor", "none",
                        "-semihosting-config", "enable=on,target=native",
                        "-icount", "shift=%d,sleep=off" % ICOUNT_SHIFT, "-kernel", elf],
                       capture_output=True, text=True, timeout=REPLY_S)
    assert r.returncode == 0, "divcheck: status %d %s" % (r.returncode, r.stdout + r.stderr)


def c_jerk_moves(b):
    """Under jerk limits (docs/jerk.md): a straight move on the S-curve, a
    blended route (its lines planned ahead in parts, between ticks) and a
    continuous goal on its jerk-limited law; each lands within a count, and
    no tick overruns."""
    expect(b, "$jerk 2000 1000", "ok jerk 2000.000 1000.000 limit 0.000 0.000")
    ready(b)
    expect(b, "moveForward 200", "ok true")
    b.settle(3000)
    expect_pos(b, 200, 0, 0)
    expect(b, "moveCruiseAbs 500 0", "ok true")
    expect(b, "moveCruiseAbs 500 300", "ok true")
    expect(b, "moveCruiseAbs 800 300", "ok true")
    b.settle(10000)
    expect_pos(b, 800, 300, 0)
    expect(b, "moveContinuousRel 100 0 90", "ok true")
    b.settle(10000)
    expect_pos(b, 900, 300, 90)
    # Off the heading, from rest (make bench's goal_jerk): the turn's and
    # the translation's tails, each planned in a tick, under tick_cost's
    # rule like every tick before it.
    expect(b, "setPosition 0 0 0", "ok true")
    expect(b, "moveContinuousRel 300 200 0", "ok true")
    b.settle(20000)
    expect_pos(b, 300, 200, 0)
    assert b.ticks()[1] == 0


def c_omni_moves(b):
    """The mecanum build (make MCU_KIN=omni): sideways, then a continuous
    goal with a heading."""
    expect(b, "getState", 'ok true 25 "Unpowered"')
    ready(b)
    expect(b, "moveLinearRel 0 100 0", "ok true")
    b.settle(3000)
    expect_pos(b, 0, 100, 0)
    expect(b, "$jerk 2000 1000", "ok jerk 2000.000 1000.000 limit 0.000 0.000")
    expect(b, "moveContinuousRel 300 -200 30", "ok true")
    b.settle(6000)
    expect(b, "getState", 'ok true 16 "Ready"')
    expect_pos(b, 300, -100, 30)
    assert b.ticks()[1] == 0


# ---- the configuration store across resets (hal/cortexm/flashstore.c) --------

TABLE = "0x916B11C3"  # vs_config_schema of this table
DIAG_END = "odom 0.000 0.000 0.000"  # $diag with no " config ..." tail


def store_line(seq, applied, torn=False):
    return "ok store loaded seq %d schema %s applied %d dropped 0 table %s%s" % (
        seq, TABLE, applied, TABLE, " torn" if torn else "")


def reboot(b):
    """A system reset through QEMU's monitor, then the board's time until it
    has booted again and ticked (board_cost starts over from zero)."""
    assert b.costs()["requests"] > 0
    b.monitor("system_reset")
    deadline = time.monotonic() + REPLY_S
    while True:
        c = b.costs()
        if c["requests"] == 0 and c["ticks"] >= 20:
            break
        assert time.monotonic() < deadline, "no boot after the reset"
        time.sleep(0.02)
    left = b.drain()
    assert left == b"", "bytes after the reset: %r" % left


def fresh_board(elf, tmp):
    """A new QEMU: its store region powers on erased (a board from the
    factory)."""
    b = Board(elf, "mps2-an386", tempfile.mkdtemp(dir=tmp))
    expect(b, "$config store", "ok store empty table %s" % TABLE)
    return b


def c_config_save_reset(elf, tmp):
    """$config NAME VALUE, $config save, a system reset: the saved values
    are in force (a restart field's too: the SysTick period), an unsaved
    change is gone, the store says which record; a save of the defaults
    reads back as none changed."""
    b = fresh_board(elf, tmp)
    try:
        # The ranges in Q32 (firmware/config.c's table): its ends taken,
        # beyond them refused.
        for line, reply in (
                ("$config wheel_diameter_mm 9.999", "error 8 $config wheel_diameter_mm: "
                 "wheel_diameter_mm: rejected by the configuration check"),
                ("$config joystick_deadband 0.501", "error 8 $config joystick_deadband: "
                 "joystick_deadband: rejected by the configuration check"),
                ("$config joystick_deadband 0.5", "ok joystick_deadband 0.500"),
                ("$config position_window_mm 0", "error 8 $config position_window_mm: "
                 "position_window_mm: rejected by the configuration check"),
                ("$config encoder_counts_per_rev 16777217", "error 8 $config "
                 "encoder_counts_per_rev: encoder_counts_per_rev: rejected by the "
                 "configuration check"),
                ("$config joystick_deadband 0.05", "ok joystick_deadband 0.050")):
            expect(b, line, reply)
        expect(b, "$config wheel_diameter_mm 160", "ok wheel_diameter_mm 160.000")
        expect(b, "$config tick_hz 500", "ok tick_hz 1000 pending 500")
        expect(b, "$config save", "ok saved 2 tick_hz wheel_diameter_mm")
        expect(b, "$config following_error_mm 60", "ok following_error_mm 60.000")
        expect(b, "$config diff",
               "ok unsaved 1 following_error_mm changed 3 tick_hz wheel_diameter_mm "
               "following_error_mm pending 1 tick_hz")
        reboot(b)
        expect(b, "$config store", store_line(1, 2))
        expect(b, "$config wheel_diameter_mm", "ok wheel_diameter_mm 160.000")
        expect(b, "$config tick_hz", "ok tick_hz 500")
        expect(b, "$config following_error_mm", "ok following_error_mm 50.000")
        expect(b, "$config diff",
               "ok unsaved 0 changed 2 tick_hz wheel_diameter_mm pending 0")
        assert b.ex("$diag").endswith(DIAG_END), "a config tail in $diag"
        expect(b, "getActiveAlarm 16", "ok true 0 0")
        # The unit runs at the saved rate: SysTick's reload for 500 Hz.
        rvr = re.findall(r"\b0x([0-9a-f]{8})\b", b.monitor("xp /1wx 0xe000e014"))
        assert int(rvr[0], 16) == CPU_HZ // 500 - 1, "SysTick reload %s" % rvr
        expect(b, "$config defaults", "ok defaults pending 1")
        expect(b, "$config save", "ok saved 0")
        reboot(b)
        expect(b, "$config store", store_line(2, 0))
        expect(b, "$config wheel_diameter_mm", "ok wheel_diameter_mm 150.000")
        expect(b, "$config tick_hz", "ok tick_hz 1000")
    finally:
        b.close()


# The third save of c_config_cut writes wheel_diameter_mm alone: a 33-byte
# payload. Its steps (flashstore.h): 1 the page erased, 2-5 the payload's
# four whole double words, 6 its last part word, 7-9 the header, 10 the
# commit word. Cut at 11: no such step, the save completes.
CUTS = (1, 4, 6, 9, 10, 11)


def c_config_cut(elf, tmp, k):
    """A reset in the middle of a save (the test image's $storecut K: step K
    done half, the board stopped until the reset): the field reads the
    value of the last save or of this one, exactly, never the defaults; a
    slot left half written is reported (torn) as on the host, and the next
    save clears it."""
    b = fresh_board(elf, tmp)
    try:
        expect(b, "$config wheel_diameter_mm 160", "ok wheel_diameter_mm 160.000")
        expect(b, "$config save", "ok saved 1 wheel_diameter_mm")
        expect(b, "$config wheel_diameter_mm 170", "ok wheel_diameter_mm 170.000")
        expect(b, "$config save", "ok saved 1 wheel_diameter_mm")
        expect(b, "$config wheel_diameter_mm 180", "ok wheel_diameter_mm 180.000")
        expect(b, "$storecut %d" % k, "ok cut")
        n = b.costs()["requests"]
        b.write(b"$config save\n")
        if k > 10:
            assert b.readline() == "ok saved 1 wheel_diameter_mm"
        else:
            # stopped in the save: no reply, the request never counted
            assert b.drain() == b"", "a reply from a save cut at step %d" % k
            assert b.costs()["requests"] == n, "the save cut at step %d ended" % k
        reboot(b)
        done = k > 10
        # Cut in the erase (its first half, where the older record lay):
        # that slot reads erased, not torn.
        torn = 1 < k <= 10
        expect(b, "$config wheel_diameter_mm",
               "ok wheel_diameter_mm %s" % ("180.000" if done else "170.000"))
        expect(b, "$config store", store_line(3 if done else 2, 1, torn))
        assert b.ex("$diag").endswith(DIAG_END), "a config tail in $diag"
        expect(b, "getActiveAlarm 16", "ok true 0 0")
        if torn:
            expect(b, "$config save", "ok saved 1 wheel_diameter_mm")
            reboot(b)
            expect(b, "$config store", store_line(3, 1))
            expect(b, "$config wheel_diameter_mm", "ok wheel_diameter_mm 170.000")
    finally:
        b.close()


def c_m0_boots(b):
    expect(b, "getState", 'ok true 25 "Unpowered"')
    ready(b)
    expect(b, "moveForward 100", "ok true")
    b.settle(1500)
    expect(b, "getState", 'ok true 16 "Ready"')
    expect_pos(b, 100, 0, 0)
    assert b.ticks()[1] == 0


def main():
    build = sys.argv[1] if len(sys.argv) > 1 else "build"
    m4 = os.path.join(build, "cortex-m4", "vehicle.elf")
    m0 = os.path.join(build, "cortex-m0", "vehicle.elf")
    omni = os.path.join(build, "cortex-m4-omni", "vehicle.elf")
    cut = os.path.join(build, "cortex-m4", "vehicle-cut.elf")
    vehiclectl = os.path.join(build, "vehiclectl")
    passed = failed = 0

    def run(name, fn, *args):
        nonlocal passed, failed
        t0 = time.monotonic()
        try:
            fn(*args)
            passed += 1
            print("ok %s (%.1f s)" % (name, time.monotonic() - t0), flush=True)
        except Exception as e:  # one case's failure must not hide the rest
            failed += 1
            print("FAIL %s: %s" % (name, e), flush=True)
            traceback.print_exc(limit=3, file=sys.stdout)
            try:
                b = args[0]
                if not isinstance(b, Board):
                    return
                left = b.drain()
                print("  then: %d bytes late (%r) | %s | %s | %s | %s"
                      % (len(left), left[:80], b.ex("getActiveAlarm 32767"), b.ex("$diag"),
                         b.ex("$link"), b.costs()))
            except Exception as e2:
                print("  no state after it: %s" % e2)

    run("div_check", c_div_check, os.path.join(build, "cortex-m4", "divcheck.elf"))
    run("tick_bench", c_tick_bench, os.path.join(build, "cortex-m4", "bench.elf"))
    with tempfile.TemporaryDirectory() as tmp:
        for elf, machine, cases in (
                (m4, "mps2-an386",
                 [("version_burst", c_version_burst, ())] +
                 [(c.__name__[2:], c, ()) for c in CONFORMANCE] +
                 [("link_watchdog", c_link_watchdog, ())] +
                 [("vehiclectl_frames", c_vehiclectl_frames, (vehiclectl,)),
                  ("bbox", c_bbox, (vehiclectl,)),
                  ("telemetry_stream", c_telemetry_stream, ()),
                  ("stream_text", c_stream_text, ()),
                  ("jerk_moves", c_jerk_moves, ()),
                  ("tick_cost", c_tick_cost, ()),
                  ("request_costs", c_request_costs, ()),
                  ("planning_costs", c_planning_costs, ())]),
                (omni, "mps2-an386", [("omni_moves", c_omni_moves, ())]),
                (m0, "mps2-an385", [("m0_boots_on_m3", c_m0_boots, ())])):
            try:
                b = Board(elf, machine, tmp)
            except Exception as e:
                failed += 1
                print("FAIL boot %s on %s: %s" % (elf, machine, e))
                continue
            print("%s on %s (-icount shift=%d), UART %s" % (elf, machine, ICOUNT_SHIFT, b.pty))
            # The cases wait in the unit's time without a request (as the
            # simulator's lockstep tests do): the link watchdog is off for
            # them, and link_watchdog tests it.
            expect(b, "$watchdog", "ok watchdog 1000")
            expect(b, "$watchdog 0", "ok watchdog 0")
            try:
                for name, fn, args in cases:
                    if fn is not cases[0][1]:
                        reset(b)
                    run(name, fn, b, *args)
                    left = b.drain()
                    if left:
                        failed += 1
                        print("FAIL %s: unexpected bytes after it: %r" % (name, left))
            finally:
                b.close()
    with tempfile.TemporaryDirectory() as tmp:
        run("config_save_reset", c_config_save_reset, m4, tmp)
        for k in CUTS:
            run("config_cut_%d" % k, c_config_cut, cut, tmp, k)
    print("mcu: %d passed, %d failed" % (passed, failed))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
