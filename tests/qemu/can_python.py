"""Independent peer for the CAN link: python-can (Debian's python3-can) speaks
the protocol of docs/can.md from the document alone, against vehicle-sim
--can vcan0 --node 1 --status-hz 10 in the QEMU guest.

Run by tests/qemu/can_peers.sh. "--list-modules" (on the host) prints the
files of every module this script imports, so that exactly those go into
the guest.
"""
import struct
import sys
import time

import can
import can.interfaces.socketcan  # noqa: F401  (loaded here, not lazily)

NODE = 1
REQ, RSP = 0x600 + NODE, 0x580 + NODE
ST_A, ST_B, ST_C = 0x180 + NODE, 0x280 + NODE, 0x380 + NODE


def fail(msg):
    print("can_python: FAIL: " + msg)
    sys.exit(1)


def segment(msg):
    """docs/can.md: single frame up to 7 bytes, else first + consecutive."""
    if len(msg) <= 7:
        return [bytes([len(msg)]) + msg]
    frames = [bytes([0x10 | len(msg) >> 8, len(msg) & 0xFF]) + msg[:6]]
    rest, index = msg[6:], 1
    while rest:
        frames.append(bytes([0x20 | (index & 15)]) + rest[:7])
        rest, index = rest[7:], index + 1
    return frames


def send(bus, data):
    bus.send(can.Message(arbitration_id=REQ, data=data, is_extended_id=False))


def recv_fc(bus, timeout=2.0):
    """docs/can.md: the unit answers a first frame with flow control."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        m = bus.recv(max(0.0, deadline - time.monotonic()))
        if m is None or m.arbitration_id != RSP or m.is_extended_id:
            continue
        if m.data[0] >> 4 == 3:
            return m.data[0] & 15, m.data[1], m.data[2]
    fail("no flow control within %.1f s" % timeout)


def recv_message(bus, timeout=2.0):
    """Reassembles the next response message."""
    deadline = time.monotonic() + timeout
    want, data, index = None, b"", 1
    while time.monotonic() < deadline:
        m = bus.recv(max(0.0, deadline - time.monotonic()))
        if m is None or m.arbitration_id != RSP or m.is_extended_id:
            continue
        pci = m.data[0] >> 4
        if pci == 0:
            return bytes(m.data[1:1 + (m.data[0] & 15)])
        if pci == 1:
            want = (m.data[0] & 15) << 8 | m.data[1]
            data, index = bytes(m.data[2:8]), 1
            send(bus, b"\x30\x00\x00")  # go on, all at once
        elif pci == 2 and want is not None:
            if m.data[0] & 15 != index & 15:
                fail("consecutive frame index %d, expected %d" % (m.data[0] & 15, index))
            data += bytes(m.data[1:1 + min(7, want - len(data))])
            index += 1
            if len(data) == want:
                return data
    fail("no response within %.1f s" % timeout)


SEQ = [0x30]


def call(bus, opcode, payload=b""):
    """Returns (status, response payload)."""
    SEQ[0] = (SEQ[0] + 1) & 0xFF
    frames = segment(bytes([SEQ[0], opcode]) + payload)
    send(bus, frames[0])
    if len(frames) > 1:
        fs, bs, _ = recv_fc(bus)
        if (fs, bs) != (0, 0):
            fail("flow control %d, block size %d: expected go on, 0" % (fs, bs))
    for f in frames[1:]:
        send(bus, f)
    msg = recv_message(bus)
    if msg[0] != SEQ[0] or msg[1] != opcode:
        fail("response header %s for seq %d opcode %d" % (msg[:2].hex(), SEQ[0], opcode))
    return msg[2], msg[3:]


def status_group(bus, timeout=2.0):
    deadline = time.monotonic() + timeout
    got = {}
    while time.monotonic() < deadline:
        m = bus.recv(0.5)
        if m is None:
            continue
        if m.arbitration_id == ST_A:
            got = {"A": bytes(m.data)}
        elif m.arbitration_id in (ST_B, ST_C) and "A" in got:
            got["B" if m.arbitration_id == ST_B else "C"] = bytes(m.data)
            if len(got) == 3:
                a = struct.unpack("<HBBHh", got["A"])
                b = struct.unpack("<ii", got["B"])
                c = struct.unpack("<ihh", got["C"])
                return {"state": a[0], "alarms": a[1], "counter": a[2], "battery_cV": a[3],
                        "vx": a[4], "x_dmm": b[0], "y_dmm": b[1], "theta_mdeg": c[0],
                        "vy": c[1], "w_ddeg": c[2]}
    fail("no status group within %.1f s" % timeout)


def string(payload, off):
    n = payload[off]
    return payload[off + 1:off + 1 + n].decode(), off + 1 + n


def main():
    if sys.argv[1:] == ["--list-modules"]:
        for m in list(sys.modules.values()):
            f = getattr(m, "__file__", None)
            if f:
                print(f)
        return
    bus = can.Bus(interface="socketcan", channel="vcan0",
                  can_filters=[{"can_id": i, "can_mask": 0x7FF, "extended": False}
                               for i in (RSP, ST_A, ST_B, ST_C)])
    try:
        # Heartbeat: three frames per group, counter +1, 10 Hz.
        g1 = status_group(bus)
        t0 = time.monotonic()
        g2 = status_group(bus)
        for _ in range(8):
            g2 = status_group(bus)
        dt = time.monotonic() - t0
        if g1["state"] != 0x19 or g1["alarms"] != 0:
            fail("status %r: expected Unpowered (0x19), no alarm" % g1)
        if (g2["counter"] - g1["counter"]) & 0xFF != 9:
            fail("status counter %d -> %d over 9 groups" % (g1["counter"], g2["counter"]))
        if not 0.5 < dt < 1.5:
            fail("9 status groups took %.2f s at 10 Hz" % dt)
        if not 2300 <= g1["battery_cV"] <= 2600:
            fail("battery %d cV" % g1["battery_cV"])
        print("can_python: status frames ok (%r)" % g1)

        st, p = call(bus, 7)  # getIFVersion: multi-frame response
        s, _ = string(p, 1)
        if st != 0 or p[0] != 1 or s != "RTC VehicleService interface: ver.2.0.0":
            fail("getIFVersion: status %d payload %s" % (st, p.hex()))
        st, p = call(bus, 0x7F)  # protocol information
        ver, crc, ops, reqmax, respmax = struct.unpack("<BHBHH", p)
        if st != 0 or ops != 34 or ver < 1:
            fail("info: status %d %r" % (st, (ver, crc, ops)))
        for op, arg in ((30, b"\x01"), (31, b"\x01")):  # setPower, setServo true
            st, p = call(bus, op, arg)
            if (st, p) != (0, b"\x01"):
                fail("opcode %d: status %d payload %s" % (op, st, p.hex()))
        st, p = call(bus, 17, struct.pack("<d", 300.0))  # moveForward 300
        if (st, p) != (0, b"\x01"):
            fail("moveForward: status %d payload %s" % (st, p.hex()))
        # Status groups until one shows the move under way: the simulator's
        # time, not the host's, decides when (bounded at 10 s of ours).
        deadline = time.monotonic() + 10
        while True:
            g = status_group(bus)
            if g["state"] == 0x11 and g["vx"] > 0:
                break
            if g["state"] != 0x11 or time.monotonic() > deadline:
                fail("while moving: %r" % g)
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:
            st, p = call(bus, 11)  # getState
            code = struct.unpack("<h", p[1:3])[0]
            if code == 0x10:
                break
            time.sleep(0.2)
        else:
            fail("moveForward 300 did not finish (state 0x%x)" % code)
        time.sleep(1.0)  # the wheels settle on the end of the trajectory
        st, p = call(bus, 9)  # getPosition
        x, y, th = struct.unpack("<ddd", p[1:])
        if st != 0 or abs(x - 300.0) > 0.05 or abs(y) > 0.05 or abs(th) > 0.05:
            fail("getPosition after moveForward 300: %r" % ((x, y, th),))
        g = status_group(bus)
        if abs(g["x_dmm"] - 3000) > 1 or g["vx"] != 0 or g["state"] != 0x10:
            fail("status after the move: %r" % g)
        # NAKs: unknown opcode (4), wrong length (3)
        if call(bus, 0x55) != (4, b""):
            fail("unknown opcode not NAKed with reason 4")
        if call(bus, 17, b"\x00\x00") != (3, b""):
            fail("short moveForward not NAKed with reason 3")
        print("can_python: requests ok, position %.3f %.3f %.3f" % (x, y, th))
    finally:
        bus.shutdown()
    print("can_python: PASS")


main()
