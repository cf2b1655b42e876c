"""The telemetry stream (docs/protocol.md, "Telemetry stream"): the value
set of proto/stream.def, its frames decoded into typed samples, and the
subscription an iterator of them.

    with vs.open_frames(port) as v:
        with v.subscribe(("pose", "state"), period_ms=100) as sub:
            for s in sub:          # Sample(seq=0, tick=..., x=..., state=16, ...)
                print(s.t, s.x, s.y, s.state)
"""
import struct
from typing import NamedTuple, Optional

OP_STREAM = 0x7D
GROUPS = ("pose", "cmd", "meas", "state", "alarm", "battery", "io", "queue")
MASK_ALL = (1 << len(GROUPS)) - 1

# proto/stream.def's rows, in its order: (name, group, struct code, scale to
# the Sample's unit). tests/python/test_stream.py checks them against the
# file.
FIELDS = (
    ("state", "state", "H", 1),
    ("alarms", "state", "B", 1),
    ("battery_cV", "battery", "H", 0.01),
    ("vx_mm_s", "cmd", "h", 1),
    ("x_dmm", "pose", "i", 0.1),
    ("y_dmm", "pose", "i", 0.1),
    ("theta_mdeg", "pose", "i", 0.001),
    ("vy_mm_s", "cmd", "h", 1),
    ("w_ddeg_s", "cmd", "h", 0.1),
    ("mvx_mm_s", "meas", "h", 1),
    ("mvy_mm_s", "meas", "h", 1),
    ("mw_ddeg_s", "meas", "h", 0.1),
    ("queue", "queue", "B", 1),
    ("alarm_type", "alarm", "B", 1),
    ("alarm_code", "alarm", "I", 1),
    ("inputs", "io", "H", 1),
    ("outputs", "io", "H", 1),
)

# The Sample's name of each row (physical units: mm, deg, mm/s, deg/s, V).
NAMES = {"state": "state", "alarms": "alarms", "battery_cV": "battery_V", "vx_mm_s": "vx",
         "x_dmm": "x", "y_dmm": "y", "theta_mdeg": "theta", "vy_mm_s": "vy", "w_ddeg_s": "w",
         "mvx_mm_s": "meas_vx", "mvy_mm_s": "meas_vy", "mw_ddeg_s": "meas_w", "queue": "queue",
         "alarm_type": "alarm_type", "alarm_code": "alarm_code", "inputs": "inputs",
         "outputs": "outputs"}


class StreamInfo(NamedTuple):
    mask: int  # groups in force (0: none)
    period_ms: int
    frame_bytes: int  # one stream frame on the wire
    min_period_ms: int  # the fastest this set may go on this line
    tick_hz: int


class Sample(NamedTuple):
    """One stream frame. Values of groups not subscribed are None."""
    seq: int  # the stream's sequence number (mod 256)
    tick: int  # the unit's control ticks since start
    t: float  # seconds of the unit's time since the subscription's first sample
    lost: int  # frames missing before this one (a gap in seq)
    mask: int
    x: Optional[float] = None  # mm, getPosition
    y: Optional[float] = None
    theta: Optional[float] = None  # deg
    vx: Optional[int] = None  # commanded, mm/s
    vy: Optional[int] = None
    w: Optional[float] = None  # deg/s
    meas_vx: Optional[int] = None  # measured, mm/s
    meas_vy: Optional[int] = None
    meas_w: Optional[float] = None  # deg/s
    state: Optional[int] = None  # getState code
    alarms: Optional[int] = None  # active alarms
    alarm_code: Optional[int] = None  # newest alarm, 0 none
    alarm_type: Optional[int] = None  # 1 fault, 2 warning, 0 none
    battery_V: Optional[float] = None
    inputs: Optional[int] = None  # bit k: k-th input of io.xml set
    outputs: Optional[int] = None
    queue: Optional[int] = None


def mask_of(groups):
    """A mask from group names ("pose", ...), "all", or an int."""
    if isinstance(groups, int):
        return groups
    if isinstance(groups, str):
        groups = (groups,)
    m = 0
    for g in groups:
        if g == "all":
            m |= MASK_ALL
        else:
            m |= 1 << GROUPS.index(g)
    return m


def frame_bytes(mask):
    """Bytes of one stream frame of mask on the wire."""
    return 13 + sum(struct.calcsize("<" + c) for _, g, c, _ in FIELDS
                    if mask >> GROUPS.index(g) & 1)


def decode(payload):
    """(mask, tick, {row name: integer}) of a stream frame's payload."""
    if len(payload) < 6:
        raise ValueError("stream frame of %d bytes" % len(payload))
    mask, tick = struct.unpack_from("<HI", payload)
    if mask & ~MASK_ALL or len(payload) != frame_bytes(mask) - 7:
        raise ValueError("stream frame: mask 0x%X, %d bytes" % (mask, len(payload)))
    at, values = 6, {}
    for gi, g in enumerate(GROUPS):
        if not mask >> gi & 1:
            continue
        for name, group, code, _ in FIELDS:
            if group == g:
                values[name] = struct.unpack_from("<" + code, payload, at)[0]
                at += struct.calcsize("<" + code)
    return mask, tick, values


class Subscription:
    """An iterator of Samples (Vehicle.subscribe); close() unsubscribes.
    next() waits up to timeout seconds for a frame (LinkTimeout)."""

    def __init__(self, vehicle, info, timeout):
        self.vehicle = vehicle
        self.info = info
        self.timeout = timeout
        self._last = None
        self._tick0 = None

    def __iter__(self):
        return self

    def __next__(self):
        if self.vehicle is None:
            raise StopIteration
        seq, payload = self.vehicle.transport.next_stream(self.timeout)
        mask, tick, raw = decode(payload)
        lost = 0 if self._last is None else (seq - self._last - 1) & 0xFF
        self._last = seq
        if self._tick0 is None:
            self._tick0 = tick
        vals = {NAMES[k]: (v * FIELD_SCALE[k] if FIELD_SCALE[k] != 1 else v) for k, v in raw.items()}
        return Sample(seq=seq, tick=tick, t=(tick - self._tick0) / (self.info.tick_hz or 1000),
                      lost=lost, mask=mask, **vals)

    def close(self):
        if self.vehicle is not None:
            self.vehicle.unsubscribe()
            self.vehicle = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


FIELD_SCALE = {name: scale for name, _, _, scale in FIELDS}

