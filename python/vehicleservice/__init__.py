"""A Python client for the vehicle unit's VehicleService interface, written
from docs/protocol.md, docs/console.md and docs/can.md: binary frames or
console lines on the serial port (python3-serial), or the CAN link
(python3-can).

    import vehicleservice as vs
    with vs.open_frames("/dev/ttyUSB0") as v:
        v.setPower(True); v.setServo(True)
        v.moveForward(500.0)
        print(v.getPosition().value)
"""
from .client import (ActiveAlarms, Acceleration, Alarm, Position, Reply, State, Vehicle,  # noqa: F401
                     Velocity, open_can, open_console, open_frames)
from .errors import ConsoleError, LinkTimeout, NakError, ProtocolError, VehicleError  # noqa: F401
from .ops import OPERATIONS, table_crc  # noqa: F401
