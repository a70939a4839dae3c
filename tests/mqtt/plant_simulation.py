#!/usr/bin/python3
"""A plant of modules on one broker: N homingd processes (simulator backend,
time-scaled) publish to Debian's mosquitto on loopback as Sparkplug B edge
nodes of one group; each is homed C times over NCMD (cmd/home_all, with
--mqtt-commands) and by Modbus in turn; an independent Sparkplug host
(paho-mqtt, python3-protobuf) counts every event of every module and checks
none is missing: per node, the event ids run without a gap and every cycle
that ran has its start and its end. Prints the figures; exits non-zero on a
missing event. Bounded: N modules, C cycles each, a time limit for the whole.

usage: plant_simulation.py HOMINGD PYTHON_DIR [--modules N] [--cycles C] [--time-limit-s S]"""
import argparse, os, sys, tempfile, time

from pymodbus.client import ModbusTcpClient

from e2e_support import (Broker, alias_names, failures, free_port, import_sparkplug, ncmd, shut_down, sparkplug_host,
                         start_homingd, wait_until)

ap = argparse.ArgumentParser()
ap.add_argument("homingd"); ap.add_argument("pydir")
ap.add_argument("--modules", type=int, default=6)
ap.add_argument("--cycles", type=int, default=4)
ap.add_argument("--time-limit-s", type=float, default=120)
args = ap.parse_args()
import_sparkplug(args.pydir)

started = time.monotonic()
work = tempfile.mkdtemp(prefix="plant-")
broker = Broker(work, "allow_anonymous true\npersistence false\nmax_queued_messages 100000\n")

births, events, counts = {}, {}, {"NBIRTH": 0, "NDATA": 0, "bytes": 0}
def on_payload(kind, node, p, msg):
    counts[kind] = counts.get(kind, 0) + 1
    counts["bytes"] += len(msg.payload)
    if kind == "NBIRTH":
        births[node] = alias_names(p)
    elif kind == "NDATA" and node in births:
        ev = {births[node].get(m.alias): m for m in p.metrics}
        if "event/id" in ev:
            events.setdefault(node, []).append((ev["event/id"].long_value, ev["event/kind"].string_value))
sub = sparkplug_host("plant-host", broker, on_payload)

modules = []
try:
    for i in range(args.modules):
        port = free_port()
        node = f"cell{i + 1}"
        p = start_homingd(args.homingd, port, os.path.join(work, node + ".db"), broker.url(), node, "--mqtt-commands")
        modules.append((node, port, p))
    ok = wait_until(lambda: len(births) == args.modules, 30)
    print(f"[plant] {len(births)} of {args.modules} modules born")
    clients = {node: ModbusTcpClient("127.0.0.1", port=port, timeout=2, retries=0) for node, port, _ in modules}
    for c in clients.values():
        wait_until(lambda: c.connect(), 10)
    def read(c, address, count):
        """Input registers, or None; a connection the module closed (idle while
        the others were waited for) is opened again."""
        try:
            r = c.read_input_registers(address, count, slave=1)
            return None if r.isError() else r.registers
        except Exception:  # pymodbus raises on a closed connection
            c.close()
            c.connect()
            return None
    def cycles_done(c):
        r = read(c, 3, 2)
        return -1 if r is None else (r[0] << 16) | r[1]
    def state(c):
        r = read(c, 1, 1)
        return None if r is None else r[0]
    ran = {node: 0 for node, _, _ in modules}
    for k in range(args.cycles):
        before = {}
        for node, c in clients.items():
            wait_until(lambda: cycles_done(c) >= 0, 10)
            before[node] = cycles_done(c)
        for node, c in clients.items():
            if k % 2 == 0:
                ncmd(sub, node, "cmd/home_all")
            else:
                try:
                    c.write_coil(0, True, slave=1)
                except Exception:
                    c.close(); c.connect(); c.write_coil(0, True, slave=1)
        for node, c in clients.items():
            if wait_until(lambda: cycles_done(c) > before[node] and state(c) not in (None, 1), 60):
                ran[node] += 1
        if time.monotonic() - started > args.time_limit_s:
            print("[plant] time limit reached"); break
    def complete():
        return all(sum(1 for _, kd in events.get(n, []) if kd == "cycle_ended") >= ran[n] for n in ran)
    wait_until(complete, 20)
    missing = []
    for node in ran:
        ids = [i for i, _ in events.get(node, [])]
        ends = sum(1 for _, kd in events.get(node, []) if kd == "cycle_ended")
        starts = sum(1 for _, kd in events.get(node, []) if kd == "cycle_started")
        gap = sorted(set(range(1, max(ids) + 1)) - set(ids)) if ids else []
        if gap or ends < ran[node] or starts < ran[node]:
            missing.append(f"{node}: ran {ran[node]}, starts {starts}, ends {ends}, missing ids {gap[:5]}")
    total_events = sum(len(v) for v in events.values())
    total_cycles = sum(ran.values())
    print(f"[plant] {args.modules} modules, {total_cycles} homing cycles, {total_events} events counted, "
          f"{counts.get('NDATA', 0)} NDATA, {counts.get('NBIRTH', 0)} NBIRTH, "
          f"{counts['bytes'] / max(total_cycles, 1):.0f} bytes on the broker per homing cycle, "
          f"{time.monotonic() - started:.1f} s")
    for line in missing:
        print("[plant] MISSING " + line)
    ok = ok and not missing and total_cycles == args.modules * args.cycles
finally:
    shut_down([p for _, _, p in modules], sub, broker)
sys.exit(0 if ok and not failures else 1)
