"""A Python client for the vehicle unit's VehicleService interface, written
from docs/protocol.md, docs/console.md and docs/can.md: binary frames or
console lines on the serial port (python3-serial), or the CAN link
(python3-can).

    import vehicleservice as vs
    with vs.open_frames("/dev/ttyUSB0") as v:
        v.setPower(True); v.setServo(True)
        v.moveForward(500.0)
        v.wait_done()          # Ready, or Warning-### while idle
        print(v.getPosition().value)
"""
from .bbox import BlackBox, BoxSample  # noqa: F401
from .client import (DONE_STATES, STOPPED_STATES, ActiveAlarms, Acceleration, Alarm,  # noqa: F401
                     Position, Reply, State, Vehicle, Velocity, open_can, open_console, open_frames)
from .errors import (ConsoleError, LinkTimeout, MotionStopped, NakError, ProtocolError,  # noqa: F401
                     VehicleError, WaitTimeout)
from .ops import OPERATIONS, AlarmType, table_crc  # noqa: F401
from .stream import GROUPS, Sample, StreamInfo, Subscription  # noqa: F401
