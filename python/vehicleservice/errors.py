"""Exceptions of the VehicleService client."""


class VehicleError(Exception):
    """Base of every error this package raises."""


class ConsoleError(VehicleError):
    """The console answered ``error <code> <message>`` (docs/console.md):
    the line did not run and nothing changed in the unit."""

    def __init__(self, code, message):
        super().__init__("error %d %s" % (code, message))
        self.code = code
        self.message = message


NAK_NAMES = {1: "crc", 2: "oversize", 3: "length", 4: "opcode", 5: "value", 6: "truncated",
             8: "rate"}


class NakError(VehicleError):
    """The unit answered a frame or CAN message with a NAK status
    (docs/protocol.md, docs/can.md): the operation did not run."""

    def __init__(self, status, opcode=None):
        self.status = status
        self.name = NAK_NAMES.get(status, "status %d" % status)
        self.opcode = opcode
        super().__init__("NAK %d (%s)%s" % (status, self.name,
                                            "" if opcode is None else " for opcode 0x%02X" % opcode))


class LinkTimeout(VehicleError, TimeoutError):
    """No valid answer within the timeout, after every retry."""


class ProtocolError(VehicleError):
    """An answer that does not follow the documented layout."""


class MotionStopped(VehicleError):
    """Vehicle.wait_done: the unit stopped short of done (a fault, Stuck,
    Locked, servo or power off; docs/console.md). state is its State,
    alarm its newest Alarm (None when none is active)."""

    def __init__(self, state, alarm=None):
        self.state = state
        self.alarm = alarm
        super().__init__("stopped short: %d %s%s" % (
            state.code, state.message,
            "" if alarm is None else " (%d %s \"%s\")" % (alarm.code, alarm.type, alarm.source)))


class WaitTimeout(VehicleError, TimeoutError):
    """Vehicle.wait_done: still busy or paused at the timeout; state is the
    last State read."""

    def __init__(self, state, timeout):
        self.state = state
        super().__init__("not done after %g s: %d %s" % (timeout, state.code, state.message))
