"""The Python client (python/vehicleservice, copied to /test) over CAN against
vehicle-sim --can vcan0 --node 1, cross-checked with the C client
(vehiclectl --can --json). Run by tests/qemu/can_peers.sh; "--list-modules"
(on the host) prints the files of the modules it imports."""
import json
import subprocess
import sys
import time

sys.path.insert(0, "/test")
import can.interfaces.socketcan  # noqa: E402,F401  (loaded here, not lazily)
import vehicleservice as vs  # noqa: E402


def fail(msg):
    print("can_vs: FAIL: " + msg)
    sys.exit(1)


def ctl(*args):
    out = subprocess.run(["vehiclectl", "--can", "vcan0", "--json"] + [str(a) for a in args],
                         capture_output=True, text=True, timeout=20)
    return json.loads(out.stdout)


def main():
    if sys.argv[1:] == ["--list-modules"]:
        for m in list(sys.modules.values()):
            f = getattr(m, "__file__", None)
            if f:
                print(f)
        return
    with vs.open_can("vcan0", node=1) as v:
        if v.protocol_info() != (1, 0x1F09, 34, 24, 1108):
            fail("protocol info %r" % (v.protocol_info(),))
        want = {
            "getIFVersion": (True, "RTC VehicleService interface: ver.2.0.0"),
            "getVersion": (True, "Ver.1.0.0"),
            "getState": (True, (25, "Unpowered")),
            "getAccelerationLimit": (True, (1000.0, 360.0)),
            "getDefaultVelocity": (True, (500.0, 90.0)),
        }
        for op, w in want.items():
            got = getattr(v, op)()
            if got != w:
                fail("%s: %r, expected %r" % (op, got, w))
        if not (v.setPower(True) and v.setServo(True) and v.setVelocity(400.0, 80.0)):
            fail("power, servo, velocity refused")
        if not v.moveLinearAbs(300.0, 0.0, 0.0):  # a 26-byte request, 4 frames
            fail("moveLinearAbs refused")
        for _ in range(200):
            if v.getState().value.code == 16:
                break
            time.sleep(0.05)
        else:
            fail("moveLinearAbs 300 did not finish")
        time.sleep(1.0)
        p = v.getPosition().value
        j = ctl("getPosition")
        # the wheels may still settle by a few µm between the two reads
        if max(abs(j["x"] - p.x), abs(j["y"] - p.y), abs(j["theta"] - p.theta)) > 0.05 or \
                abs(p.x - 300.0) > 0.05:
            fail("getPosition %r, vehiclectl %r" % (p, j))
        j = ctl("getVelocityLimit")
        if (j["result"], j["velLimitT"], j["velLimitR"]) != (True, *v.getVelocityLimit().value):
            fail("getVelocityLimit: vehiclectl %r" % j)
        if v.moveJog(0.0, 5.0, 0.0) is not False:  # no sideways on two wheels
            fail("sideways jog not refused")
        al = v.getActiveAlarm(16).value
        j = ctl("getActiveAlarm", 16)
        if [(a.code, a.source) for a in al.alarms] != \
                [(a["code"], a["source"]) for a in j["activeAlarms"]] or al.count < 1:
            fail("alarms %r, vehiclectl %r" % (al, j))
        try:
            v.transport.exchange(0x55, b"")
            fail("unknown opcode answered")
        except vs.NakError as e:
            if e.status != 4:
                fail("NAK %d for an unknown opcode" % e.status)
    print("can_vs: PASS: vehicleservice over CAN matches the unit and vehiclectl")


main()
