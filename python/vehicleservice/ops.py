"""The VehicleService operations as docs/protocol.md lists them, and the
encoding of their arguments (little-endian, no padding).

Type codes: b boolean, h short, u unsigned long, d double, s string,
a alarm sequence.
"""
import enum
import struct

from .errors import ProtocolError

PROTOCOL_VERSION = 1
OP_INFO = 0x7F
# one console line in a frame (docs/protocol.md): the bring-up extras
OP_CONSOLE = 0x7E

# name: (opcode, in types, out types), from the opcode table of docs/protocol.md
OPERATIONS = {
    "clearAlarm": (0x01, "", ""),
    "getAccelerationLimit": (0x02, "", "dd"),
    "getActiveAlarm": (0x03, "h", "ha"),
    "getBatteryVoltage": (0x04, "", "d"),
    "getDefaultAcceleration": (0x05, "", "dd"),
    "getDefaultVelocity": (0x06, "", "dd"),
    "getIFVersion": (0x07, "", "s"),
    "getInput": (0x08, "u", "u"),
    "getPosition": (0x09, "", "ddd"),
    "getServoStatus": (0x0A, "u", "b"),
    "getState": (0x0B, "", "hs"),
    "getVelocityLimit": (0x0C, "", "dd"),
    "getVersion": (0x0D, "", "s"),
    "moveCircularRel": (0x0E, "ddd", ""),
    "moveContinuousRel": (0x0F, "ddd", ""),
    "moveCruiseAbs": (0x10, "dd", ""),
    "moveForward": (0x11, "d", ""),
    "moveJog": (0x12, "ddd", ""),
    "moveLinearAbs": (0x13, "ddd", ""),
    "moveLinearRel": (0x14, "ddd", ""),
    "moveTurn": (0x15, "d", ""),
    "pause": (0x16, "", ""),
    "resume": (0x17, "", ""),
    "setAcceleration": (0x18, "dd", ""),
    "setDigitalSensorLock": (0x19, "b", ""),
    "setJogTimeout": (0x1A, "h", ""),
    "setJoystick": (0x1B, "b", ""),
    "setOutput": (0x1C, "uuu", ""),
    "setPosition": (0x1D, "ddd", ""),
    "setPower": (0x1E, "b", ""),
    "setServo": (0x1F, "b", ""),
    "setVelocity": (0x20, "dd", ""),
    "stop": (0x21, "", ""),
    "unlock": (0x22, "", ""),
}
BY_OPCODE = {v[0]: k for k, v in OPERATIONS.items()}



class AlarmType(enum.IntEnum):
    """The IDL's AlarmType: a number (== 2, int() == 2) whose str is its name
    as the console and vehiclectl write it ("warning")."""
    unknown = 0
    fault = 1
    warning = 2

    def __str__(self):
        return self.name

    def __format__(self, spec):
        # "{:d}" and the like format the number, anything else the name
        if spec and spec[-1] in "bcdoxXneEfFgG%":
            return format(int(self), spec)
        return format(self.name, spec)


ALARM_FAULT, ALARM_WARNING = AlarmType.fault, AlarmType.warning
ALARM_TYPES = {t.name: t for t in AlarmType}


def alarm_type(value):
    """AlarmType of a type number; a number the IDL does not name stays an int."""
    try:
        return AlarmType(value)
    except ValueError:
        return value


def crc16(data, crc=0xFFFF):
    """CRC-16/CCITT-FALSE: polynomial 0x1021, initial 0xFFFF, no reflection."""
    for byte in data:
        crc ^= byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) & 0xFFFF if crc & 0x8000 else (crc << 1) & 0xFFFF
    return crc


def table_crc():
    """The command table's checksum as docs/console.md defines it: the text
    'name:opcode:in:out\\n' of every row in opcode order."""
    text = "".join("%s:%d:%s:%s\n" % (BY_OPCODE[op], op, OPERATIONS[BY_OPCODE[op]][1],
                                         OPERATIONS[BY_OPCODE[op]][2])
                   for op in sorted(BY_OPCODE))
    return crc16(text.encode())


def _check_int(code, value):
    if isinstance(value, bool) or not isinstance(value, int):
        raise TypeError("expected an int, got %r" % (value,))
    lo, hi = (-32768, 32767) if code == "h" else (0, 0xFFFFFFFF)
    if not lo <= value <= hi:
        raise ValueError("%d is outside %d..%d" % (value, lo, hi))


def encode_args(types, args):
    """The request payload of in-arguments args."""
    if len(args) != len(types):
        raise TypeError("takes %d arguments, got %d" % (len(types), len(args)))
    out = bytearray()
    for code, value in zip(types, args):
        if code == "b":
            if not isinstance(value, bool):
                raise TypeError("expected a bool, got %r" % (value,))
            out.append(1 if value else 0)
        elif code == "h":
            _check_int(code, value)
            out += struct.pack("<h", value)
        elif code == "u":
            _check_int(code, value)
            out += struct.pack("<I", value)
        elif code == "d":
            out += struct.pack("<d", float(value))
        else:
            raise ValueError("no in-argument of type %r" % code)
    return bytes(out)


def decode_outs(types, data):
    """Result boolean and out-arguments of a response payload (after the
    status byte), as a list [result, out...]; strings and alarm sources as
    str (UTF-8, undecodable bytes escaped)."""
    pos = 0

    def take(n):
        nonlocal pos
        if pos + n > len(data):
            raise ProtocolError("response payload too short: %s" % data.hex())
        chunk = data[pos:pos + n]
        pos += n
        return chunk

    def string():
        n = take(1)[0]
        return take(n).decode("utf-8", "backslashreplace")

    values = []
    result = take(1)[0]
    if result > 1:
        raise ProtocolError("result byte %d" % result)
    values.append(bool(result))
    for code in types:
        if code == "b":
            b = take(1)[0]
            if b > 1:
                raise ProtocolError("boolean byte %d" % b)
            values.append(bool(b))
        elif code == "h":
            values.append(struct.unpack("<h", take(2))[0])
        elif code == "u":
            values.append(struct.unpack("<I", take(4))[0])
        elif code == "d":
            values.append(struct.unpack("<d", take(8))[0])
        elif code == "s":
            values.append(string())
        elif code == "a":
            count = take(1)[0]
            alarms = []
            for _ in range(count):
                code_, type_ = struct.unpack("<IB", take(5))
                alarms.append((code_, alarm_type(type_), string()))
            values.append(alarms)
    if pos != len(data):
        raise ProtocolError("%d bytes after the response" % (len(data) - pos))
    return values


def decode_info(data):
    """The protocol information (opcode 0x7F) after the status byte."""
    if len(data) != 8:
        raise ProtocolError("protocol information of %d bytes" % len(data))
    return struct.unpack("<BHBHH", data)
