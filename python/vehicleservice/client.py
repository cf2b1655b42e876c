"""One method per VehicleService operation (../shared/spec/VehicleService.md),
over binary frames, the console or CAN.

Operations without out-arguments return their boolean result; the others a
Reply(result, value) with a typed value. A refused operation is not an
exception: result False (the unit raises a warning alarm saying why).
Exceptions: ConsoleError for an ``error`` line, NakError for a NAK,
LinkTimeout when nothing came back; wait_done's MotionStopped and
WaitTimeout.
"""
import math
import struct
import time
from typing import Generic, List, NamedTuple, TypeVar

from . import bbox as _bbox
from .errors import ConsoleError, MotionStopped, ProtocolError, WaitTimeout
from .ops import (ALARM_TYPES, OP_CONSOLE, OPERATIONS, PROTOCOL_VERSION, AlarmType, decode_info,
                  decode_outs, encode_args, table_crc)
from .stream import OP_STREAM, StreamInfo, Subscription, mask_of
from .transport import CanTransport, ConsoleTransport, FrameTransport

T = TypeVar("T")


class Reply(NamedTuple, Generic[T]):
    result: bool
    value: T


class Position(NamedTuple):
    x: float  # mm
    y: float  # mm
    theta: float  # deg


class Velocity(NamedTuple):
    translation: float  # mm/s
    rotation: float  # deg/s


class Acceleration(NamedTuple):
    translation: float  # mm/s^2
    rotation: float  # deg/s^2


class State(NamedTuple):
    code: int  # 16 Ready ... 25 Unpowered
    message: str


# What getState's code means to a host that waits (docs/console.md,
# "Waiting for a motion"; spec 6.9): an idle unit with a warning active
# reads Warning-###, which is done as much as Ready is.
DONE_STATES = frozenset((16, 18))  # Ready, Warning-###
STOPPED_STATES = frozenset((19, 20, 23, 24, 25))  # Alarm-###, Stuck, Locked, Powered, Unpowered


class Alarm(NamedTuple):
    code: int
    type: AlarmType  # == 1 fault, 2 warning; str() gives "fault", "warning"
    source: str


class ActiveAlarms(NamedTuple):
    count: int  # active alarms, whatever was asked
    alarms: List[Alarm]  # newest first


def _console_words(text):
    """Splits a reply into words; a double-quoted string is one word with
    \\", \\\\ and \\xHH undone (docs/console.md)."""
    words, i = [], 0
    while i < len(text):
        if text[i] == " ":
            i += 1
            continue
        if text[i] != '"':
            j = text.find(" ", i)
            j = len(text) if j < 0 else j
            words.append(text[i:j])
            i = j
            continue
        out, i = bytearray(), i + 1
        while True:
            if i >= len(text):
                raise ProtocolError("unterminated string in %r" % text)
            c = text[i]
            if c == '"':
                i += 1
                break
            if c == "\\":
                nxt = text[i + 1:i + 2]
                if nxt == "x":
                    out.append(int(text[i + 2:i + 4], 16))
                    i += 4
                    continue
                out += nxt.encode()
                i += 2
                continue
            out += c.encode()
            i += 1
        words.append(out.decode("utf-8", "backslashreplace"))
    return words


def _console_value(code, v):
    if code == "b":
        return "true" if v else "false"
    if code == "d":
        v = float(v)
        if not math.isfinite(v):
            return repr(v)  # the console answers error 3
        return repr(v)
    return str(int(v))


def _parse_console(outs, text):
    words = _console_words(text)
    if not words or words[0] not in ("true", "false"):
        raise ProtocolError("reply %r" % text)
    values, k = [words[0] == "true"], 1
    try:
        for code in outs:
            if code == "b":
                values.append({"true": True, "false": False}[words[k]])
                k += 1
            elif code in "hu":
                values.append(int(words[k]))
                k += 1
            elif code == "d":
                values.append(float(words[k]))
                k += 1
            elif code == "s":
                values.append(words[k])
                k += 1
            elif code == "a":
                n = int(words[k])
                k += 1
                alarms = []
                for _ in range(n):
                    alarms.append((int(words[k]), ALARM_TYPES[words[k + 1]], words[k + 2]))
                    k += 3
                values.append(alarms)
    except (IndexError, KeyError, ValueError):
        raise ProtocolError("reply %r does not fit %r" % (text, outs)) from None
    if k != len(words):
        raise ProtocolError("reply %r has %d words too many" % (text, len(words) - k))
    return values


class Vehicle:
    """A VehicleService client over one transport (see open_frames,
    open_console, open_can)."""

    def __init__(self, transport):
        self.transport = transport
        self.console = isinstance(transport, ConsoleTransport)

    def close(self):
        self.transport.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def protocol_info(self):
        """(version, table checksum, operations, largest request, largest
        response); raises ProtocolError when the unit's command table is
        not the one this package was written for."""
        if self.console:
            raise NotImplementedError("binary transports only ($version on the console)")
        info = decode_info(self.transport.info)
        if info[0] != PROTOCOL_VERSION or info[1] != table_crc() or info[2] != len(OPERATIONS):
            raise ProtocolError("unit speaks protocol %d, table 0x%04X, %d operations; "
                                "this client %d, 0x%04X, %d" % (info[0], info[1], info[2],
                                                              PROTOCOL_VERSION, table_crc(),
                                                              len(OPERATIONS)))
        return info

    def call(self, name, *args):
        """[result, out...] of operation name."""
        opcode, ins, outs = OPERATIONS[name]
        encode_args(ins, args)  # the same checks on every transport
        if self.console:
            line = " ".join([name] + [_console_value(c, v) for c, v in zip(ins, args)])
            return _parse_console(outs, self.transport.command(line))
        return decode_outs(outs, self.transport.exchange(opcode, encode_args(ins, args)))

    def console_line(self, line: str) -> str:
        """Runs one console line (docs/console.md: a bring-up extra such
        as ``$config ...``) and returns its reply after "ok " ("" for a
        bare "ok"); raises ConsoleError for "error ...". Over frames the
        line travels in a console frame (at most 64 bytes); CAN has none
        (NakError)."""
        if "\n" in line or "\r" in line or not line:
            raise ValueError("one line")
        if self.console:
            return self.transport.command(line)
        data = line.encode("ascii")
        if len(data) > 64:
            raise ValueError("a console line in a frame has at most 64 bytes")
        reply = self.transport.exchange(OP_CONSOLE, data).decode("ascii", "backslashreplace")
        if reply == "ok" or reply.startswith("ok "):
            return reply[3:]
        if reply.startswith("error "):
            code, _, msg = reply[6:].partition(" ")
            raise ConsoleError(int(code), msg)
        raise ProtocolError("reply %r" % reply)

    def config(self, *args) -> str:
        """``$config ARGS``: a field's value (``config("tick_hz")``), a
        change (``config("wheel_diameter_mm", 160)``, ``config("drive_lag_ms[1]",
        25)``), ``config("diff")``, ``"save"``, ``"defaults"``, ``"reload"``,
        ``"store"``; the reply after "ok " (docs/console.md), ConsoleError
        for a refusal."""
        return self.console_line(" ".join(["$config"] + [str(a) for a in args]))

    def subscribe(self, groups="all", period_ms: int = 100, timeout: float = 2.0) -> Subscription:
        """The telemetry stream (docs/protocol.md, "Telemetry stream"):
        the groups ("pose", "cmd", "meas", "state", "alarm", "battery",
        "io", "queue", "all", or a mask) every period_ms, as an iterator of
        typed Samples whose next() waits up to timeout s; close() (or the
        with block's end) unsubscribes. A rate the line cannot carry:
        NakError with name "rate". Binary frames only."""
        if not isinstance(self.transport, FrameTransport):
            raise NotImplementedError("the stream is on binary frames only")
        mask = mask_of(groups)
        r = self.transport.exchange(OP_STREAM, struct.pack("<HH", mask, period_ms))
        if len(r) != 10:
            raise ProtocolError("subscription answer of %d bytes" % len(r))
        return Subscription(self, StreamInfo(*struct.unpack("<5H", r)), timeout)

    def unsubscribe(self) -> None:
        """Ends the stream (mask 0)."""
        self.transport.exchange(OP_STREAM, struct.pack("<HH", 0, 0))

    def read_bbox(self) -> "_bbox.BlackBox":
        """The black box (docs/protocol.md, "Black box"), every sample, page
        by page: read it frozen (a ring still recording moves between
        pages). Binary frames only."""
        if not isinstance(self.transport, FrameTransport):
            raise NotImplementedError("the black box is read on binary frames only")
        return _bbox.read(self.transport.exchange)

    def clear_bbox(self) -> None:
        """Empties the black box and re-arms it."""
        if not isinstance(self.transport, FrameTransport):
            raise NotImplementedError("the black box is read on binary frames only")
        _bbox.clear(self.transport.exchange)

    def _ok(self, name, *args) -> bool:
        return self.call(name, *args)[0]

    # ---- operations, in opcode order --------------------------------------
    def clearAlarm(self) -> bool:
        return self._ok("clearAlarm")

    def getAccelerationLimit(self) -> Reply[Acceleration]:
        r = self.call("getAccelerationLimit")
        return Reply(r[0], Acceleration(*r[1:]))

    def getActiveAlarm(self, numOfAlarm: int) -> Reply[ActiveAlarms]:
        r = self.call("getActiveAlarm", numOfAlarm)
        return Reply(r[0], ActiveAlarms(r[1], [Alarm(*a) for a in r[2]]))

    def getBatteryVoltage(self) -> Reply[float]:
        r = self.call("getBatteryVoltage")
        return Reply(r[0], r[1])

    def getDefaultAcceleration(self) -> Reply[Acceleration]:
        r = self.call("getDefaultAcceleration")
        return Reply(r[0], Acceleration(*r[1:]))

    def getDefaultVelocity(self) -> Reply[Velocity]:
        r = self.call("getDefaultVelocity")
        return Reply(r[0], Velocity(*r[1:]))

    def getIFVersion(self) -> Reply[str]:
        r = self.call("getIFVersion")
        return Reply(r[0], r[1])

    def getInput(self, ioid: int) -> Reply[int]:
        r = self.call("getInput", ioid)
        return Reply(r[0], r[1])

    def getPosition(self) -> Reply[Position]:
        r = self.call("getPosition")
        return Reply(r[0], Position(*r[1:]))

    def getServoStatus(self, axisid: int) -> Reply[bool]:
        r = self.call("getServoStatus", axisid)
        return Reply(r[0], r[1])

    def getState(self) -> Reply[State]:
        r = self.call("getState")
        return Reply(r[0], State(r[1], r[2]))

    def getVelocityLimit(self) -> Reply[Velocity]:
        r = self.call("getVelocityLimit")
        return Reply(r[0], Velocity(*r[1:]))

    def getVersion(self) -> Reply[str]:
        r = self.call("getVersion")
        return Reply(r[0], r[1])

    def moveCircularRel(self, x: float, y: float, theta: float) -> bool:
        return self._ok("moveCircularRel", x, y, theta)

    def moveContinuousRel(self, x: float, y: float, theta: float) -> bool:
        return self._ok("moveContinuousRel", x, y, theta)

    def moveCruiseAbs(self, x: float, y: float) -> bool:
        return self._ok("moveCruiseAbs", x, y)

    def moveForward(self, x: float) -> bool:
        return self._ok("moveForward", x)

    def moveJog(self, xVel: float, yVel: float, thetaVel: float) -> bool:
        return self._ok("moveJog", xVel, yVel, thetaVel)

    def moveLinearAbs(self, x: float, y: float, theta: float) -> bool:
        return self._ok("moveLinearAbs", x, y, theta)

    def moveLinearRel(self, x: float, y: float, theta: float) -> bool:
        return self._ok("moveLinearRel", x, y, theta)

    def moveTurn(self, theta: float) -> bool:
        return self._ok("moveTurn", theta)

    def pause(self) -> bool:
        return self._ok("pause")

    def resume(self) -> bool:
        return self._ok("resume")

    def setAcceleration(self, translation: float, rotation: float) -> bool:
        return self._ok("setAcceleration", translation, rotation)

    def setDigitalSensorLock(self, on: bool) -> bool:
        return self._ok("setDigitalSensorLock", on)

    def setJogTimeout(self, ms: int) -> bool:
        return self._ok("setJogTimeout", ms)

    def setJoystick(self, on: bool) -> bool:
        return self._ok("setJoystick", on)

    def setOutput(self, ioid: int, output: int, mask: int) -> bool:
        return self._ok("setOutput", ioid, output, mask)

    def setPosition(self, x: float, y: float, theta: float) -> bool:
        return self._ok("setPosition", x, y, theta)

    def setPower(self, on: bool) -> bool:
        return self._ok("setPower", on)

    def setServo(self, on: bool) -> bool:
        return self._ok("setServo", on)

    def setVelocity(self, translation: float, rotation: float) -> bool:
        return self._ok("setVelocity", translation, rotation)

    def stop(self) -> bool:
        return self._ok("stop")

    def unlock(self) -> bool:
        return self._ok("unlock")

    # ---- waiting ------------------------------------------------------------
    def wait_done(self, timeout: float = 300.0, poll: float = 0.02) -> State:
        """Polls getState every poll seconds (which feeds the link watchdog)
        until the unit is done: Ready or Warning-### (a warning left by any
        refused request keeps an idle unit at Warning-### until clearAlarm).
        Returns that State. Raises MotionStopped when it stopped short (a
        fault, Stuck, Locked, servo or power off) and WaitTimeout when it is
        still busy or paused after timeout seconds."""
        end = time.monotonic() + timeout
        while True:
            st = self.getState().value
            if st.code in DONE_STATES:
                return st
            if st.code in STOPPED_STATES:
                alarms = self.getActiveAlarm(1).value.alarms
                raise MotionStopped(st, alarms[0] if alarms else None)
            if time.monotonic() >= end:
                raise WaitTimeout(st, timeout)
            time.sleep(poll)


def open_frames(port, **kw) -> Vehicle:
    """Binary frames on a serial port path or pyserial object."""
    return Vehicle(FrameTransport(port, **kw))


def open_console(port, **kw) -> Vehicle:
    """Console lines on a serial port path or pyserial object."""
    return Vehicle(ConsoleTransport(port, **kw))


def open_can(channel="vcan0", node=1, **kw) -> Vehicle:
    """The CAN link through python-can (default interface socketcan)."""
    return Vehicle(CanTransport(channel, node, **kw))
