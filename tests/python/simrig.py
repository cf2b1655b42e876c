"""vehicle-sim --pty for the Python client's tests: started per test case,
ended by its process id."""
import os
import subprocess

TOP = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BUILD = os.environ.get("VEHICLE_BUILD", os.path.join(TOP, "build"))


class Sim:
    def __init__(self):
        self.proc = subprocess.Popen(
            [os.path.join(BUILD, "vehicle-sim"), "--pty", "--config",
             os.path.join(TOP, "config/vehicle.xml"), "--io", os.path.join(TOP, "config/io.xml")],
            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, stdin=subprocess.DEVNULL)
        self.path = self.proc.stdout.readline().decode().strip()
        if not self.path.startswith("/dev/"):
            raise RuntimeError("vehicle-sim printed %r" % self.path)

    def close(self):
        self.proc.terminate()
        self.proc.wait(10)
        self.proc.stdout.close()


def vehiclectl(path, *args):
    out = subprocess.run([os.path.join(BUILD, "vehiclectl"), "--port", path, "--json"] +
                         [str(a) for a in args], capture_output=True, text=True, timeout=20)
    return out.returncode, out.stdout
