#!/usr/bin/python3
"""Independent check of mbdrive-sim's register map with pymodbus (Debian's
python3-pymodbus), the client side of the bus that vehicle-fw uses.

    mb_crosscheck.py PORT SIM_PID [BATTERY_UNIT BATTERY_MV]

With a battery (mbdrive-sim --battery), also its registers: the voltage in
10 mV counts at input register 0x200 and holding register 0x108, in mV as
uint32 (high word first) at input registers 0x201-0x202.

Prints one "crosscheck: FAIL: ..." line and exits 1 on the first mismatch,
"crosscheck: PASS" at the end.
"""
import os
import signal
import sys
import time

from pymodbus.client import ModbusSerialClient

BASE = 0x100
BAT_INPUT, BAT_HOLDING = 0x200, 0x108
SPEED, POS, STATUS, ALARM, SERVO, RESET = 0, 2, 4, 5, 6, 7


def fail(msg):
    print("crosscheck: FAIL: " + msg)
    sys.exit(1)


def s32(hi, lo):
    v = (hi << 16) | lo
    return v - (1 << 32) if v & 0x80000000 else v


def main():
    port, sim = sys.argv[1], int(sys.argv[2])
    # Whole seconds: pymodbus 3.0 truncates the timeout to an int.
    c = ModbusSerialClient(port=port, baudrate=115200, timeout=1)
    if not c.connect():
        fail("cannot open " + port)

    def regs(unit):
        r = c.read_holding_registers(BASE, 8, slave=unit)
        if r.isError():
            fail("unit %d: read: %s" % (unit, r))
        return r.registers

    def write(unit, off, values):
        r = c.write_registers(BASE + off, values, slave=unit)
        if r.isError():
            fail("unit %d: write %#x: %s" % (unit, BASE + off, r))

    def expect(what, got, want):
        if got != want:
            fail("%s: got %r, expected %r" % (what, got, want))

    r = regs(1)
    expect("unit 1 at start: position, status, alarm", (s32(r[POS], r[POS + 1]), r[STATUS], r[ALARM]), (0, 0, 0))

    # Servo on and +100000 counts/s (int32, high word first): the
    # position grows at that rate; status bit 0 set.
    write(1, SERVO, [1])
    write(1, SPEED, [0x0001, 0x86A0])
    t0 = time.monotonic()
    time.sleep(0.3)
    r = regs(1)
    dt = time.monotonic() - t0
    pos = s32(r[POS], r[POS + 1])
    expect("unit 1 status with servo on", r[STATUS], 1)
    expect("unit 1 target speed readback", (r[SPEED], r[SPEED + 1]), (0x0001, 0x86A0))
    if not 100000 * (dt - 0.1) < pos <= 100000 * (dt + 0.01):
        fail("unit 1 position after %.3f s at 100000 counts/s: %d" % (dt, pos))

    # Negative speed: two's complement across both registers.
    write(1, SPEED, [0xFFFF, 0xEC78])  # -5000
    time.sleep(0.2)
    p2 = s32(*regs(1)[POS:POS + 2])
    if not p2 < pos + 100000 * 0.05:
        fail("unit 1 position did not fall at -5000 counts/s: %d then %d" % (pos, p2))

    # Unit 2 on the same bus is independent.
    r = regs(2)
    expect("unit 2 untouched", (s32(r[POS], r[POS + 1]), r[STATUS], r[SERVO]), (0, 0, 0))

    # The drive's alarm: status drops; fault reset clears it.
    os.kill(sim, signal.SIGUSR2)
    time.sleep(0.05)
    r = regs(1)
    expect("unit 1 alarm code", r[ALARM], 0x31)
    expect("unit 1 status with alarm", r[STATUS], 0)
    write(1, RESET, [1])
    r = regs(1)
    expect("unit 1 after fault reset: alarm, status", (r[ALARM], r[STATUS]), (0, 1))

    write(1, SPEED, [0, 0])
    write(1, SERVO, [0])
    expect("unit 1 status with servo off", regs(1)[STATUS], 0)

    if len(sys.argv) > 4:
        unit, mv = int(sys.argv[3]), int(sys.argv[4])
        r = c.read_input_registers(BAT_INPUT, 3, slave=unit)
        if r.isError():
            fail("unit %d: read input registers: %s" % (unit, r))
        expect("battery input 0x200 (10 mV)", r.registers[0], mv // 10)
        expect("battery input 0x201-0x202 (mV)", (r.registers[1] << 16) | r.registers[2], mv)
        expect("battery input high word", r.registers[1], mv >> 16)
        r = c.read_holding_registers(BAT_HOLDING, 1, slave=unit)
        if r.isError():
            fail("unit %d: read holding 0x108: %s" % (unit, r))
        expect("battery holding 0x108 (10 mV)", r.registers[0], mv // 10)
    c.close()
    print("crosscheck: PASS")


def list_modules():
    """The files of every module a request loads, for a guest without the
    host's Python tree (tests/qemu/fw_process.sh): one read on a pty nobody
    answers goes through the same client, framer and transport code."""
    import pty
    master, slave = pty.openpty()
    c = ModbusSerialClient(port=os.ttyname(slave), baudrate=115200, timeout=0.05)
    c.connect()
    c.read_holding_registers(BASE, 1, slave=1)
    c.close()
    os.close(master)
    os.close(slave)
    for m in list(sys.modules.values()):
        f = getattr(m, "__file__", None)
        if f:
            print(f)


if sys.argv[1:] == ["--list-modules"]:
    list_modules()
else:
    main()
