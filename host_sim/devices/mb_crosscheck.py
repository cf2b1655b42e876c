#!/usr/bin/python3
"""Independent check of mbdrive-sim's register map with pymodbus (Debian's
python3-pymodbus), the client side of the bus that vehicle-fw uses.

    mb_crosscheck.py PORT SIM_PID [BATTERY_UNIT BATTERY_MV]
    mb_crosscheck.py --profile zlac8015d PORT SIM_PID

The first form: the generic profile at the example map (holding 0x100..).
The second: mbdrive-sim --profile zlac8015d (speed_scale 4096/60), one
unit (1) with two motors, as the ZLAC8015D's register map has them (the
addresses below are this script's own, from that map, not vehicle-fw's).

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


def zlac(port, sim):
    """The ZLAC8015D's map: control word 0x200E (8 enable, 7 stop, 6 clear
    fault), r/min as int16 at 0x2088 (left) and 0x2089 (right), position
    int32 high word first at 0x20A7 and 0x20A9, fault codes 0x20A5 and
    0x20A6, status 0x20A2 bit 0."""
    counts_per_rpm = 4096 / 60.0  # the profile's speed_scale: 4096 counts a turn
    c = ModbusSerialClient(port=port, baudrate=115200, timeout=1)
    if not c.connect():
        fail("cannot open " + port)

    def read(addr, n):
        r = c.read_holding_registers(addr, n, slave=1)
        if r.isError():
            fail("read %#x: %s" % (addr, r))
        return r.registers

    def write(addr, v):
        r = c.write_register(addr, v & 0xFFFF, slave=1)
        if r.isError():
            fail("write %#x: %s" % (addr, r))

    def expect(what, got, want):
        if got != want:
            fail("%s: got %r, expected %r" % (what, got, want))

    def positions():
        r = read(0x20A7, 4)
        return s32(r[0], r[1]), s32(r[2], r[3])

    expect("positions at start", positions(), (0, 0))
    expect("status at start", read(0x20A2, 1)[0] & 1, 0)
    write(0x200E, 0x08)
    expect("status enabled", read(0x20A2, 1)[0] & 1, 1)
    # +120 r/min left, -60 r/min right (two's complement in 16 bits)
    write(0x2088, 120)
    write(0x2089, -60)
    t0 = time.monotonic()
    time.sleep(0.3)
    left, right = positions()
    dt = time.monotonic() - t0
    expect("speed readback", read(0x2088, 2), [120, 0x10000 - 60])
    if not 120 * counts_per_rpm * (dt - 0.1) < left <= 120 * counts_per_rpm * (dt + 0.01):
        fail("left position after %.3f s at 120 r/min: %d" % (dt, left))
    if not -60 * counts_per_rpm * (dt + 0.01) <= right < -60 * counts_per_rpm * (dt - 0.1):
        fail("right position after %.3f s at -60 r/min: %d" % (dt, right))
    # the left motor's fault: both stop (one control word); clear fault
    os.kill(sim, signal.SIGUSR2)
    time.sleep(0.05)
    expect("fault codes", read(0x20A5, 2), [0x31, 0])
    expect("status with a fault", read(0x20A2, 1)[0] & 1, 0)
    write(0x200E, 0x06)
    expect("fault codes after clear", read(0x20A5, 2), [0, 0])
    expect("status after clear (still enabled)", read(0x20A2, 1)[0] & 1, 1)
    write(0x200E, 0x07)
    expect("status stopped", read(0x20A2, 1)[0] & 1, 0)
    p1 = positions()
    time.sleep(0.1)
    expect("positions stand when stopped", positions(), p1)
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
elif sys.argv[1:3] == ["--profile", "zlac8015d"]:
    zlac(sys.argv[3], int(sys.argv[4]))
else:
    main()
