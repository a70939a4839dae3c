"""What the Python end-to-end tests share (run with Debian's /usr/bin/python3):
homingd started on free 127.0.0.1 ports by PID, its log in a file, and the
check()/failures bookkeeping. The C++ tests have the same in tests/support.
"""
import os
import select
import signal
import socket
import subprocess
import sys
import time
import types

# Debian's pymodbus 3.0 imports serial_asyncio for its serial clients even
# when only TCP is used; python3-serial-asyncio may be absent.
try:
    import serial_asyncio  # noqa: F401
except ImportError:
    _stub = types.ModuleType("serial_asyncio")
    _stub.create_serial_connection = None
    sys.modules["serial_asyncio"] = _stub

failures = []

# How each sanitizer's report begins (the same as tests/support/homingd.cpp).
SANITIZER_MARKS = ("ERROR: AddressSanitizer", "ERROR: LeakSanitizer", "SUMMARY: AddressSanitizer",
                   "SUMMARY: LeakSanitizer", "SUMMARY: UndefinedBehaviorSanitizer", "runtime error:")


def check(cond, what):
    print(f"{'ok  ' if cond else 'FAIL'} {what}")
    if not cond:
        failures.append(what)
    return cond


def free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


class Daemon:
    """homingd with Modbus TCP on a free port (and `ports - 1` more free ports
    for extra(ports) to use), ready once it printed its `listening` line.
    Five tries: a free port may be taken by someone else in between."""

    def __init__(self, exe, db, extra=lambda ports: [], ports=1, time_scale=10):
        self.proc = None
        self.log_path = db + ".log"
        last = ""
        for _ in range(5):
            self.ports = [free_port() for _ in range(ports)]
            self.port = self.ports[0]
            with open(self.log_path, "wb") as log:
                self.proc = subprocess.Popen(
                    [exe, "--tcp", f"127.0.0.1:{self.port}", "--db", db, "--time-scale", str(time_scale)]
                    + extra(self.ports),
                    stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=log)
            line = b""
            deadline = time.monotonic() + 10
            while time.monotonic() < deadline and b"\n" not in line:
                ready, _, _ = select.select([self.proc.stdout], [], [], 0.2)
                if ready:
                    chunk = os.read(self.proc.stdout.fileno(), 512)
                    if not chunk:
                        break
                    line += chunk
            if b"listening" in line:
                return
            last = line.decode(errors="replace")
            self.kill()
        raise RuntimeError(f"homingd did not start: {last!r}")

    def log_has(self, *parts, timeout=5):
        """A line of the log holds every part (bounded wait)."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            with open(self.log_path, errors="replace") as f:
                if any(all(p in line for p in parts) for line in f):
                    return True
            time.sleep(0.05)
        return False

    def finish(self):
        """Stops it as a service manager does (SIGTERM) and checks its end:
        exit 0 and no sanitizer report in its stderr (the log), so that a leak
        or a use-after-free at shutdown fails the sanitized build's run.
        Prints the log when something is wrong."""
        code = self.stop()
        ok = check(code == 0, f"SIGTERM: homingd exited {code}")
        with open(self.log_path, errors="replace") as f:
            log = f.read()
        reports = [line for line in log.splitlines() if any(m in line for m in SANITIZER_MARKS)]
        ok = check(not reports, f"no sanitizer report in homingd's stderr: {reports[:5]}") and ok
        if not ok:
            print("--- homingd log ---\n" + log)
        return ok

    def stop(self, sig=signal.SIGTERM, timeout=20):
        self.proc.send_signal(sig)
        try:
            return self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            self.kill()
            return None

    def kill(self):
        if self.proc and self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(5)
