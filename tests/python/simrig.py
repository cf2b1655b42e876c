"""vehicle-sim --pty for the Python client's tests: started per test case,
ended by its process id."""
import os
import subprocess
import tty

TOP = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BUILD = os.environ.get("VEHICLE_BUILD", os.path.join(TOP, "build"))


class Sim:
    def __init__(self, watchdog=True):
        self.proc = subprocess.Popen(
            [os.path.join(BUILD, "vehicle-sim"), "--pty", "--config",
             os.path.join(TOP, "config/vehicle.xml"), "--io", os.path.join(TOP, "config/io.xml")],
            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, stdin=subprocess.DEVNULL)
        self.path = self.proc.stdout.readline().decode().strip()
        if not self.path.startswith("/dev/"):
            raise RuntimeError("vehicle-sim printed %r" % self.path)
        if not watchdog:
            self.watchdog_off()

    def watchdog_off(self):
        """For cases whose pauses between requests last as long as a loaded
        host makes them (the watchdog has its own tests)."""
        got = self.console("$watchdog 0")
        if got != "ok watchdog 0":
            raise RuntimeError("vehicle-sim answered %r to $watchdog 0" % got)

    def console(self, line):
        """One console line on the port ('$sim ...' too), its reply without
        the line ending; between a client's requests, never during one."""
        fd = os.open(self.path, os.O_RDWR | os.O_NOCTTY)
        try:
            tty.setraw(fd)
            os.write(fd, line.encode() + b"\n")
            got = b""
            while not got.endswith(b"\n"):
                got += os.read(fd, 64)
            return got[:-1].decode()
        finally:
            os.close(fd)

    def close(self):
        self.proc.terminate()
        self.proc.wait(10)
        self.proc.stdout.close()


def vehiclectl(path, *args):
    out = subprocess.run([os.path.join(BUILD, "vehiclectl"), "--port", path, "--json"] +
                         [str(a) for a in args], capture_output=True, text=True, timeout=20)
    return out.returncode, out.stdout


# Reply timeouts for a simulator in real time on a loaded host: generous,
# so that only a unit that does not answer fails a case.
FRAMES = {"timeout": 5.0, "retries": 2}
CONSOLE = {"timeout": 15.0}
