"""What the MQTT end-to-end scripts in this directory share (run with Debian's
/usr/bin/python3, which puts this directory on sys.path): the ok/FAIL
bookkeeping, free ports, bounded waits, Debian's mosquitto on a port of
loopback, an independent Sparkplug host (paho-mqtt, payloads decoded by
python3-protobuf from the project's sparkplug_b.proto) and homingd started as
an edge node of the group `plant`.

Every script inserts the build's python directory with import_sparkplug()
before it uses the host or ncmd()."""
import os
import signal
import socket
import subprocess
import sys
import time

import paho.mqtt.client as paho

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from homingd_py import SANITIZER_MARKS  # noqa: E402  (how each sanitizer's report begins)

failures = []
started = []  # every homingd start_homingd() started: (process, its log's path)
spb = None  # the project's sparkplug_b_pb2, once import_sparkplug() ran


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        failures.append(what)
    return cond


def free_port():
    s = socket.socket(); s.bind(("127.0.0.1", 0)); p = s.getsockname()[1]; s.close(); return p


def wait_until(pred, timeout=10.0):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if pred(): return True
        time.sleep(0.05)
    return pred()


def import_sparkplug(pydir):
    """The payload classes generated into the build's python directory."""
    global spb
    sys.path.insert(0, pydir)
    import sparkplug_b_pb2
    spb = sparkplug_b_pb2
    return spb


class Broker:
    """Debian's mosquitto listening on 127.0.0.1:port, its configuration file
    in work: the listener line, then `settings` (anonymous and without
    persistence unless told otherwise). start() again after stop() brings the
    same broker back on the same port."""

    def __init__(self, work, settings="allow_anonymous true\npersistence false\n"):
        self.port = free_port()
        self.conf = os.path.join(work, "mosquitto.conf")
        with open(self.conf, "w") as f:
            f.write(f"listener {self.port} 127.0.0.1\n{settings}")
        self.proc = None
        self.start()

    def start(self):
        self.proc = subprocess.Popen(["/usr/sbin/mosquitto", "-c", self.conf], stdout=subprocess.DEVNULL,
                                     stderr=subprocess.DEVNULL)

    def stop(self):
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM); self.proc.wait()

    def url(self, scheme="mqtt"):
        return f"{scheme}://127.0.0.1:{self.port}"


def split_topic(topic):
    """spBv1.0/<group>/<type>/<node>: (type, node)."""
    parts = topic.split("/")
    return parts[2], parts[3]


def sparkplug_host(client_id, broker, on_payload, setup=None, subscribe=True, started="mosquitto did not start"):
    """A paho client that decodes every message into a Sparkplug payload and
    hands on_payload(type, node, payload, msg) each, connected to the broker
    (waiting up to 10 s for it to start), subscribed to spBv1.0/plant/# with
    QoS 1 (unless subscribe is False: setup's on_connect does it) and its
    network loop started. setup(client) runs before the connection (TLS, a
    Will, callbacks)."""
    client = paho.Client(client_id=client_id)

    def on_message(_c, _u, msg):
        p = spb.Payload()
        try:
            p.ParseFromString(msg.payload)
        except Exception:  # not Sparkplug (a test's garbage NCMD): a host ignores it; raising would end paho's loop
            return
        kind, node = split_topic(msg.topic)
        on_payload(kind, node, p, msg)
    client.on_message = on_message
    if setup:
        setup(client)

    def try_connect():
        try:
            return client.connect("127.0.0.1", broker.port) == 0
        except OSError:
            return False
    assert wait_until(try_connect, 10), started
    if subscribe:
        client.subscribe("spBv1.0/plant/#", qos=1)
    client.loop_start()
    return client


def ncmd(client, node, name, value=True, retain=False):
    """An NCMD to a node of the group plant: one Boolean metric, QoS 1 (retained
    only to show a module ignores what the specification forbids)."""
    cmd = spb.Payload()
    m = cmd.metrics.add(); m.name = name; m.datatype = spb.Boolean; m.boolean_value = value
    return client.publish(f"spBv1.0/plant/NCMD/{node}", cmd.SerializeToString(), qos=1, retain=retain)


def alias_names(birth):
    """alias -> metric name, from an NBIRTH."""
    return {m.alias: m.name for m in birth.metrics if m.HasField("alias")}


def start_homingd(homingd, modbus_port, db, mqtt_url, node, *extra, log=None, time_scale=20):
    """homingd with Modbus TCP on 127.0.0.1:modbus_port and normal scheduling,
    an edge node `node` of the group plant on mqtt_url; time_scale None: real
    time. Its output goes to log (an open file), else to db + ".log": either
    is read for sanitizer reports when the script ends (check_daemon_logs)."""
    args = [homingd, "--tcp", f"127.0.0.1:{modbus_port}", "--db", db, "--rt-priority", "0"]
    if time_scale is not None:
        args += ["--time-scale", str(time_scale)]
    args += ["--mqtt", mqtt_url, "--mqtt-group", "plant", "--mqtt-node", node, *extra]
    if log is None:
        log = open(db + ".log", "ab")
    p = subprocess.Popen(args, stdout=log, stderr=subprocess.STDOUT)
    started.append((p, log.name))
    return p


def stop_daemons(procs):
    """SIGTERM to every one still running, then each gets 10 s to end before
    SIGKILL. One that was running must end as a service manager expects: exit 0
    (a sanitizer's abort at shutdown, a hang or a crash fails the script)."""
    stopped = [p for p in procs if p.poll() is None]
    for p in stopped:
        p.send_signal(signal.SIGTERM)
    for p in procs:
        try:
            p.wait(10)
        except subprocess.TimeoutExpired:
            p.kill(); p.wait()
    for p in stopped:
        check(p.returncode == 0, f"SIGTERM: homingd (pid {p.pid}) exited {p.returncode}")


def check_daemon_logs():
    """Every homingd this script started that has ended ended as told: exit 0
    (SIGTERM) or killed by SIGKILL on purpose (a power cut), never a crash or
    an exit of its own; and no sanitizer report in any of their outputs. A log
    with a report is printed."""
    for p, _ in started:
        code = p.poll()
        if code is not None:
            check(code in (0, -signal.SIGKILL), f"homingd (pid {p.pid}) ended with {code}: neither exit 0 after SIGTERM nor a SIGKILL on purpose")
    pids = {}
    for p, path in started:
        pids.setdefault(path, []).append(str(p.pid))  # a restarted daemon may write the same log
    for path, of in pids.items():
        with open(path, errors="replace") as f:
            log = f.read()
        reports = [line for line in log.splitlines() if any(m in line for m in SANITIZER_MARKS)]
        if not check(not reports, f"no sanitizer report in the output of homingd (pid {', '.join(of)}): {reports[:3]}"):
            print(f"--- {path} ---\n" + log)


def shut_down(daemons, host, broker):
    """What every script does last, whatever happened: its homingd processes
    stopped (stop_daemons) and their logs read (check_daemon_logs), the host's
    network loop, the broker."""
    stop_daemons(daemons)
    check_daemon_logs()
    host.loop_stop()
    broker.stop()


def input_register(mb, address):
    """One input register of the module (unit 1), or None on an exception."""
    r = mb.read_input_registers(address, 1, slave=1)
    return None if r.isError() else r.registers[0]
