#!/usr/bin/python3
"""Wheel drives of the generic register map (hal/modbus/mbprofile.c) on
pymodbus's RTU server (Debian's python3-pymodbus): a peer the project did
not write, for the board's Modbus master (tests/mcu/mcu_drives.py).

Holding registers from 0x100 per unit: 0x100-0x101 target speed (int32
counts/s, high word first), 0x102-0x103 position (int32 counts), 0x104
status (bit 0: stage on), 0x105 alarm, 0x106 enable (1/0), 0x107 reset,
0x109 communication timeout (ms; taken, not acted on). The stage is on
while the enable register holds 1; the position integrates the target
speed over the drives' time while it is on: the host's, or from a line
"clock US" on stdin on, the master's (a board in an emulator: its time is
not the host's), advanced only by those lines and acknowledged with the
same line on stdout, as build/mbdrive-sim does.

  /usr/bin/python3 tests/mcu/mb_peer.py PORT UNIT...
Prints "ready" once serving.
"""
import sys
import threading
import time

from pymodbus.datastore import (ModbusSequentialDataBlock, ModbusServerContext,
                                ModbusSlaveContext)
from pymodbus.server import StartSerialServer
from pymodbus.transaction import ModbusRtuFramer

BASE = 0x100


class Clock:
    """The drives' time, s: the host's until the master gives its own."""

    def __init__(self):
        self.given = None  # the master's last time, us
        self.t = time.monotonic()

    def now(self):
        return self.t if self.given is not None else time.monotonic()

    def take(self, us):
        if self.given is None:
            self.t = time.monotonic()
        elif us > self.given:
            self.t += (us - self.given) / 1e6
        self.given = us


CLOCK = Clock()
LOCK = threading.Lock()


def control():
    for line in sys.stdin:
        w = line.split()
        if len(w) == 2 and w[0] == "clock" and w[1].isdigit():
            # under the drives' lock: no request is half served meanwhile
            with LOCK:
                CLOCK.take(int(w[1]))
            print(line.strip(), flush=True)


def s32(hi, lo):
    v = hi << 16 | lo
    return v - (1 << 32) if v & 0x80000000 else v


class Drive(ModbusSequentialDataBlock):
    def __init__(self):
        super().__init__(BASE, [0] * 10)
        self.pos = 0.0
        self.t = CLOCK.now()

    def _advance(self):
        v = super().getValues(BASE, 7)
        now = CLOCK.now()
        on = v[6] == 1
        if on:
            self.pos += s32(v[0], v[1]) * (now - self.t)
        self.t = now
        p = int(round(self.pos)) & 0xFFFFFFFF
        super().setValues(BASE + 2, [p >> 16, p & 0xFFFF, 1 if on else 0])

    def setValues(self, address, values):
        with LOCK:
            self._advance()
            super().setValues(address, values)
            self._advance()

    def getValues(self, address, count=1):
        with LOCK:
            self._advance()
            return super().getValues(address, count)


def main():
    port = sys.argv[1]
    units = [int(u) for u in sys.argv[2:]] or [1, 2]
    slaves = {u: ModbusSlaveContext(hr=Drive(), zero_mode=True) for u in units}
    context = ModbusServerContext(slaves=slaves, single=False)
    threading.Thread(target=control, daemon=True).start()
    print("ready", flush=True)
    StartSerialServer(context=context, framer=ModbusRtuFramer, port=port, baudrate=115200,
                      timeout=0.005)


if __name__ == "__main__":
    main()
