"""The black box (docs/protocol.md, "Black box"): the unit's last samples of
its control loop, frozen on the first fault, read out page by page.

    with vs.open_frames(port) as v:
        box = v.read_bbox()        # BlackBox(status="frozen", fault=204, ...)
        box.write("bbox.csv")      # the trace's columns (docs/trace.md)
        v.clear_bbox()
"""
import struct
from typing import List, NamedTuple

OP_BBOX = 0x7C
PAGE = 8
HEADER = struct.Struct("<BBHHHHHII")  # status, n, count, index, cap, every, tick_hz, trigger, fault
SAMPLE = struct.Struct("<9q4i4iIIhBB")
STATUS = ("off", "armed", "frozen")
COLUMNS = ("time_s,cmd_x_mm,cmd_y_mm,cmd_th_deg,odo_x_mm,odo_y_mm,odo_th_deg,"
           "cmd_vx_mm_s,cmd_vy_mm_s,cmd_w_deg_s,sp0_cps,sp1_cps,sp2_cps,sp3_cps,"
           "state,queue_len,alarms,newest_alarm,enc0,enc1,enc2,enc3,tick,fault")
Q32 = 4294967296.0


class BoxSample(NamedTuple):
    """One tick: the reference and odometry (mm, deg), the commanded body
    velocity (mm/s, deg/s), wheel setpoints (counts/s), encoders (counts),
    state, queue, active alarms, newest alarm code."""
    tick: int
    time_s: float
    ref: tuple
    odo: tuple
    cmd: tuple
    sp_cps: tuple
    enc: tuple
    state: int
    queue_len: int
    alarms: int
    newest_alarm: int


class BlackBox(NamedTuple):
    status: str
    capacity: int
    every: int
    tick_hz: int
    trigger: int  # the trigger sample's tick, 0 when not frozen
    fault: int    # the fault that froze it, 0 when not frozen
    samples: List[BoxSample]

    def rows(self):
        """The header and one CSV row per sample, as vehiclectl bbox writes
        them (the trigger row's fault column holds the code)."""
        out = [COLUMNS]
        for s in self.samples:
            cells = ["%.6f" % s.time_s]
            cells += ["%.4f" % v for v in s.ref + s.odo]
            cells += ["%.3f" % v for v in s.cmd]
            cells += ["%.2f" % v for v in s.sp_cps]
            cells += ["%d" % v for v in (s.state, s.queue_len, s.alarms, s.newest_alarm)]
            cells += ["%d" % v for v in s.enc]
            cells += ["%d" % s.tick, "%d" % (self.fault if s.tick == self.trigger else 0)]
            out.append(",".join(cells))
        return out

    def write(self, path):
        with open(path, "w") as f:
            f.write("\n".join(self.rows()) + "\n")


def decode_page(payload):
    """(header fields as a dict, samples) of one answer."""
    if len(payload) < HEADER.size:
        raise ValueError("black box answer of %d bytes" % len(payload))
    h = dict(zip(("status", "n", "count", "index", "cap", "every", "tick_hz", "trigger", "fault"),
                 HEADER.unpack_from(payload)))
    if len(payload) != HEADER.size + h["n"] * SAMPLE.size or h["n"] > PAGE:
        raise ValueError("black box answer of %d bytes for %d samples" % (len(payload), h["n"]))
    hz = h["tick_hz"] or 1
    samples = []
    for i in range(h["n"]):
        v = SAMPLE.unpack_from(payload, HEADER.size + i * SAMPLE.size)
        q = v[0:9]
        samples.append(BoxSample(
            tick=v[17], time_s=(v[17] * 1000000 // hz) / 1e6,
            ref=tuple(x / Q32 for x in q[0:3]), odo=tuple(x / Q32 for x in q[3:6]),
            cmd=tuple(x / Q32 * hz for x in q[6:9]), sp_cps=tuple(x / 256.0 for x in v[9:13]),
            enc=tuple(v[13:17]), state=v[19], queue_len=v[20], alarms=v[21],
            newest_alarm=v[18]))
    return h, samples


def read(exchange):
    """The whole black box through exchange(opcode, payload) -> answer."""
    samples, h = [], None
    while True:
        h, got = decode_page(exchange(OP_BBOX, struct.pack("<BH", 0, len(samples))))
        samples += got
        if not got or len(samples) >= h["count"]:
            break
    return BlackBox(STATUS[h["status"]] if h["status"] < 3 else str(h["status"]), h["cap"],
                    h["every"], h["tick_hz"], h["trigger"], h["fault"], samples)


def clear(exchange):
    decode_page(exchange(OP_BBOX, struct.pack("<BH", 1, 0)))
