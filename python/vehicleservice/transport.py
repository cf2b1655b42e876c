"""Transports: the serial port's binary frames and console lines
(docs/protocol.md, docs/console.md) and the CAN link (docs/can.md).

A binary transport's exchange(opcode, payload) returns the response payload
after the status byte, or raises NakError / LinkTimeout; the console
transport's command(line) returns the words after "ok" or raises
ConsoleError.
"""
import collections
import os
import struct
import time

from .errors import ConsoleError, LinkTimeout, NakError, ProtocolError
from .ops import OP_INFO, crc16

SYNC = 0xA5
NAK_CRC, NAK_TRUNCATED = 1, 6
OP_STREAM = 0x7D
STREAM_KEEP = 256  # stream frames kept while waiting for answers


def _open_serial(port, baudrate):
    import serial  # python3-serial

    return serial.Serial(port, baudrate=baudrate, timeout=0.05)


class FrameTransport:
    """Binary frames on a serial port (a pyserial Serial, or a path).

    Retries a request with the same seq and bytes after a timeout or a NAK
    crc/truncated, as docs/protocol.md asks; sends the protocol-info request
    first so that the first request is never taken for a repeat."""

    def __init__(self, port, baudrate=115200, timeout=0.5, retries=2, seq=None):
        self.own = isinstance(port, str)  # a port passed in stays open on close()
        self.ser = _open_serial(port, baudrate) if self.own else port
        self.timeout = timeout
        self.retries = retries
        self.seq = (os.getpid() ^ time.monotonic_ns()) & 0xFF if seq is None else seq & 0xFF
        self._buf = bytearray()
        self._stream = collections.deque(maxlen=STREAM_KEEP)
        self.info = self.exchange(OP_INFO, b"")

    def close(self):
        if self.own:
            self.ser.close()

    def next_stream(self, timeout):
        """(seq, payload) of the next stream frame the unit sent (kept
        while waiting for answers, or read now); LinkTimeout after
        timeout seconds without one."""
        deadline = time.monotonic() + timeout
        while not self._stream:
            got = self._read_frame(deadline)
            if got is None:
                raise LinkTimeout("no stream frame within %.3f s" % timeout)
            self._keep(got)
        return self._stream.popleft()

    def _keep(self, got):
        """Keeps a frame the unit sent on its own; True when it was one."""
        seq, op, data = got
        if op != OP_STREAM:
            return False
        self._stream.append((seq, data))
        return True

    @staticmethod
    def encode(seq, op, payload):
        head = struct.pack("<HBB", len(payload), seq, op) + payload
        return bytes([SYNC]) + head + struct.pack("<H", crc16(head))

    def _read_frame(self, deadline):
        """The next frame with a good check, as (seq, op, payload); bytes
        outside frames (console lines) are skipped."""
        while True:
            while len(self._buf) >= 7:
                start = self._buf.find(bytes([SYNC]))
                if start < 0:
                    self._buf.clear()
                    break
                del self._buf[:start]
                if len(self._buf) < 7:
                    break
                n = self._buf[1] | self._buf[2] << 8
                if n > 1109:
                    del self._buf[0]
                    continue
                if len(self._buf) < 7 + n:
                    break
                frame = bytes(self._buf[:7 + n])
                if crc16(frame[1:5 + n]) != (frame[5 + n] | frame[6 + n] << 8):
                    del self._buf[0]
                    continue
                del self._buf[:7 + n]
                return frame[3], frame[4], frame[5:5 + n]
            left = deadline - time.monotonic()
            if left <= 0:
                return None
            self.ser.timeout = min(left, 0.05)
            self._buf += self.ser.read(max(1, self.ser.in_waiting))

    def exchange(self, opcode, payload):
        self.seq = (self.seq + 1) & 0xFF
        frame = self.encode(self.seq, opcode, payload)
        for _ in range(self.retries + 1):
            self.ser.write(frame)
            self.ser.flush()
            deadline = time.monotonic() + self.timeout
            while True:
                got = self._read_frame(deadline)
                if got is None:
                    break  # timeout: the same frame again
                if self._keep(got):
                    continue  # a stream frame, not an answer
                seq, op, data = got
                if seq != self.seq or not data:
                    continue  # an answer to an earlier request
                if op == (opcode | 0x80):
                    if data[0] == 0:
                        return data[1:]
                    raise NakError(data[0], opcode)
                if op == 0x80:
                    if data[0] in (NAK_CRC, NAK_TRUNCATED):
                        break  # damaged on the way: retransmit
                    raise NakError(data[0], opcode)
        raise LinkTimeout("no answer to opcode 0x%02X within %.3f s, %d attempts"
                          % (opcode, self.timeout, self.retries + 1))


class ConsoleTransport:
    """Console lines on a serial port: one request line, one reply line."""

    def __init__(self, port, baudrate=115200, timeout=1.0):
        self.own = isinstance(port, str)
        self.ser = _open_serial(port, baudrate) if self.own else port
        self.timeout = timeout
        self._buf = bytearray()
        # A line ending closes whatever a previous user left half typed;
        # its reply, if any, is read and dropped.
        self.ser.write(b"\n")
        self.ser.flush()
        time.sleep(0.05)
        self.ser.reset_input_buffer()

    def close(self):
        if self.own:
            self.ser.close()

    def _read_line(self, deadline):
        while True:
            i = self._buf.find(b"\n")
            if i >= 0:
                line = bytes(self._buf[:i])
                del self._buf[:i + 1]
                return line.decode("ascii", "backslashreplace")
            left = deadline - time.monotonic()
            if left <= 0:
                return None
            self.ser.timeout = min(left, 0.05)
            self._buf += self.ser.read(max(1, self.ser.in_waiting))

    def command(self, line):
        """Sends one line; returns the reply's text after "ok " ("" for a
        bare "ok")."""
        if "\n" in line or "\r" in line:
            raise ValueError("one line at a time")
        self.ser.write(line.encode("utf-8") + b"\n")
        self.ser.flush()
        deadline = time.monotonic() + self.timeout
        while True:
            reply = self._read_line(deadline)
            if reply is None:
                raise LinkTimeout("no reply to %r within %.3f s" % (line, self.timeout))
            if reply == "ok" or reply.startswith("ok "):
                return reply[3:]
            if reply.startswith("error "):
                code, _, msg = reply[6:].partition(" ")
                try:
                    raise ConsoleError(int(code), msg)
                except ValueError:
                    raise ProtocolError("reply %r" % reply) from None
            # anything else (a stray binary answer) is not ours: read on


class CanTransport:
    """The CAN link through python-can (python3-can): ISO 15765-2
    segmentation and flow control as docs/can.md describes, node N's
    identifiers 0x600+N (requests) and 0x580+N (responses)."""

    def __init__(self, channel="vcan0", node=1, interface="socketcan", bus=None,
                 timeout=0.5, retries=2, seq=None):
        import can  # python3-can

        if not 1 <= node <= 127:
            raise ValueError("node 1..127")
        self.can = can
        self.req_id, self.rsp_id = 0x600 + node, 0x580 + node
        self.bus = bus or can.Bus(interface=interface, channel=channel,
                                  can_filters=[{"can_id": self.rsp_id, "can_mask": 0x7FF,
                                                "extended": False}])
        self.timeout = timeout
        self.retries = retries
        self.seq = (os.getpid() ^ time.monotonic_ns()) & 0xFF if seq is None else seq & 0xFF
        self.info = self.exchange(OP_INFO, b"")

    def close(self):
        self.bus.shutdown()

    def _send(self, data):
        self.bus.send(self.can.Message(arbitration_id=self.req_id, data=data,
                                       is_extended_id=False))

    def _recv(self, deadline):
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                return None
            m = self.bus.recv(left)
            if (m is not None and m.arbitration_id == self.rsp_id and not m.is_extended_id
                    and not m.is_remote_frame and m.dlc > 0):
                return bytes(m.data[:m.dlc])

    @staticmethod
    def segments(msg):
        if len(msg) <= 7:
            return [bytes([len(msg)]) + msg]
        frames = [bytes([0x10 | len(msg) >> 8, len(msg) & 0xFF]) + msg[:6]]
        for i, off in enumerate(range(6, len(msg), 7), start=1):
            frames.append(bytes([0x20 | (i & 15)]) + msg[off:off + 7])
        return frames

    def _send_message(self, msg, deadline):
        """False when the unit's flow control did not come in time."""
        frames = self.segments(msg)
        self._send(frames[0])
        rest = frames[1:]
        while rest:
            d = self._recv(deadline)
            if d is None:
                return False
            if d[0] >> 4 != 3 or len(d) < 3:
                continue  # a late answer to something else
            if d[0] & 15 == 1:
                deadline = time.monotonic() + self.timeout
                continue
            if d[0] & 15 != 0:
                return True  # overflow: the unit's NAK follows
            block, stmin = d[1] or len(rest), d[2]
            for f in rest[:block]:
                self._send(f)
                if stmin:
                    time.sleep(stmin / 1000.0 if stmin <= 0x7F else 0.0001 * (stmin - 0xF0)
                               if 0xF1 <= stmin <= 0xF9 else 0.127)
            rest = rest[block:]
        return True

    def _recv_message(self, deadline):
        want, data, index = None, b"", 1
        while True:
            d = self._recv(deadline)
            if d is None:
                return None
            pci = d[0] >> 4
            if pci == 0 and 1 <= d[0] & 15 <= min(7, len(d) - 1):
                return d[1:1 + (d[0] & 15)]
            if pci == 1 and len(d) == 8:
                want = (d[0] & 15) << 8 | d[1]
                data, index = d[2:8], 1
                self._send(b"\x30\x00\x00")  # go on: block size 0, STmin 0
            elif pci == 2 and want is not None:
                if d[0] & 15 != index & 15:
                    want = None  # lost a frame: wait for the next start
                    continue
                data += d[1:1 + min(7, want - len(data))]
                index += 1
                if len(data) == want:
                    return data

    def exchange(self, opcode, payload):
        self.seq = (self.seq + 1) & 0xFF
        msg = bytes([self.seq, opcode]) + payload
        for _ in range(self.retries + 1):
            deadline = time.monotonic() + self.timeout
            if not self._send_message(msg, deadline):
                continue
            while True:
                r = self._recv_message(deadline)
                if r is None:
                    break
                if len(r) < 3 or r[0] != self.seq or r[1] != opcode:
                    continue
                if r[2] != 0:
                    raise NakError(r[2], opcode)
                return r[3:]
        raise LinkTimeout("no answer to opcode 0x%02X within %.3f s, %d attempts"
                          % (opcode, self.timeout, self.retries + 1))
