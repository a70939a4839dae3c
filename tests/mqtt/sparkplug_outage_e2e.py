#!/usr/bin/python3
"""End-to-end: nothing is lost while the broker is away. homingd publishes to
Debian's mosquitto on loopback; the broker is stopped; over Modbus the module
homes several times, is aborted into an alarm, reset, has a setting changed,
and is killed with SIGKILL (a power cut) and started again; then the broker
comes back. An independent Sparkplug subscriber (paho-mqtt, python3-protobuf)
must then receive every one of those events, as historical metrics with the
times they happened, oldest first, with no id missing.

usage: sparkplug_outage_e2e.py HOMINGD PYTHON_DIR"""
import json, os, signal, sys, tempfile, time

from pymodbus.client import ModbusTcpClient

import e2e_support
from e2e_support import (Broker, check, failures, free_port, import_sparkplug, ncmd, shut_down, sparkplug_host,
                         wait_until)
from e2e_support import input_register as ir

homingd, pydir = sys.argv[1], sys.argv[2]
import_sparkplug(pydir)

work = tempfile.mkdtemp(prefix="mqtt-outage-e2e-")
broker = Broker(work)
modbus_port = free_port()

messages = []  # (type, Payload, arrival time)
# The subscriber is the plant's primary host: on every connection it says it
# is online (retained, as Sparkplug 3.0 asks), and its Will says offline.
STATE = "spBv1.0/STATE/e2e-host"
host_online = True
def on_connect(c, _u, _f, rc):
    if rc == 0:
        c.subscribe("spBv1.0/plant/#", qos=1)
        c.publish(STATE, json.dumps({"online": host_online, "timestamp": int(time.time() * 1000)}), qos=1, retain=True)
def primary_host(client):
    client.will_set(STATE, json.dumps({"online": False, "timestamp": int(time.time() * 1000)}), qos=1, retain=True)
    client.on_connect = on_connect
    client.reconnect_delay_set(min_delay=1, max_delay=1)
sub = sparkplug_host("outage-e2e-host", broker, lambda kind, _node, p, _msg: messages.append((kind, p, time.time())),
                     setup=primary_host, subscribe=False)

def of(kind): return [p for t, p, _ in messages if t == kind]
log = open(os.path.join(work, "homingd.log"), "a")
def start_homingd():
    return e2e_support.start_homingd(homingd, modbus_port, os.path.join(work, "h.db"), broker.url(), "m1",
                                     "--mqtt-keepalive-s", "5", "--mqtt-primary-host", "e2e-host", log=log)

def modbus():
    mb = ModbusTcpClient("127.0.0.1", port=modbus_port, timeout=2, retries=0)
    assert wait_until(lambda: mb.connect(), 10), "Modbus does not connect"
    return mb

def cycles_done(mb):  # status.homing_cycles: u32, high word first
    r = mb.read_input_registers(3, 2, slave=1)
    return -1 if r.isError() else (r.registers[0] << 16) | r.registers[1]

def home_and_wait(mb):
    before = cycles_done(mb)
    mb.write_coil(0, True, slave=1)  # cmd.home_all
    return wait_until(lambda: cycles_done(mb) > before and ir(mb, 1) != 1, 60)

daemon = start_homingd()
try:
    check(wait_until(lambda: len(of("NBIRTH")) >= 1, 15), "the module is born on the broker")
    birth = of("NBIRTH")[-1]
    alias = {m.name: m.alias for m in birth.metrics if m.HasField("alias")}
    event_names = ["event/id", "event/kind", "event/axis", "event/code", "event/duration_ms", "event/axes",
                   "event/setting", "event/old_value", "event/new_value", "event/text", "event/dropped"]
    check(all(n in alias for n in event_names), "the birth declares the event metrics")
    name_of = {a: n for n, a in alias.items()}

    # The broker goes away.
    broker.stop()
    outage_start = time.time()
    mb = modbus()
    # An alarm: the first cycle (the long one, from power-up) aborted.
    mb.write_coil(0, True, slave=1)  # cmd.home_all
    check(wait_until(lambda: ir(mb, 1) == 1, 10), "a cycle runs")
    time.sleep(0.05)
    mb.write_coil(1, True, slave=1)  # cmd.abort
    check(wait_until(lambda: ir(mb, 1) == 3, 20), "the aborted cycle ends in an alarm")
    mb.write_coil(2, True, slave=1)  # cmd.reset_alarm
    check(wait_until(lambda: ir(mb, 1) != 3, 10), "the alarm is reset")
    cycles = 0
    for _ in range(3):
        cycles += home_and_wait(mb)
    check(cycles == 3, "three homing cycles while the broker is away")
    old_feed = mb.read_holding_registers(102, 1, slave=1).registers[0]
    mb.write_register(102, old_feed + 7, slave=1)  # axis.x.seek_feedrate
    time.sleep(1.0)  # the settings change reaches the outbox within the monitor's half second
    mb.close()
    # A power cut while the broker is away, and the module starts again.
    daemon.send_signal(signal.SIGKILL); daemon.wait()
    daemon = start_homingd()
    mb = modbus()
    check(home_and_wait(mb), "a fourth cycle after the restart, broker still away")
    mb.close()
    outage_end = time.time()
    seen_before = len(messages)

    # The broker comes back: every event arrives, historical, oldest first.
    broker.start()
    def events():
        out = []
        for t, p, _ in messages[seen_before:]:
            if t != "NDATA": continue
            ev = {name_of.get(m.alias): m for m in p.metrics if name_of.get(m.alias, "").startswith("event/")}
            if "event/id" in ev: out.append(ev)
        return out
    def ended(): return [e for e in events() if e["event/kind"].string_value == "cycle_ended"]
    check(wait_until(lambda: len(ended()) >= 5, 40), "every cycle's end arrives after the broker is back (4 homed + 1 aborted)")
    # The bdSeq of the birth after the power cut is none an earlier session
    # registered: a host still holding that session's death certificate
    # (a Will delivered late) cannot take it for this one's.
    def bd_seq(p): return {m.name: m for m in p.metrics}["bdSeq"].long_value
    earlier = [bd_seq(p) for t, p, _ in messages[:seen_before] if t == "NBIRTH"]
    later = [bd_seq(p) for t, p, _ in messages[seen_before:] if t == "NBIRTH"]
    check(later and later[0] not in earlier, f"the birth after the restart takes a new bdSeq: {later[:1]} after {earlier}")
    time.sleep(1.0)
    evs = events()
    kinds = [e["event/kind"].string_value for e in evs]
    print("events:", kinds)
    ids = [e["event/id"].long_value for e in evs]
    check(ids == sorted(ids) and len(set(ids)) == len(ids), f"oldest first, each once: {ids}")
    check(ids == list(range(ids[0], ids[0] + len(ids))) if ids else False, "no event id missing")
    check(all(m.is_historical for e in evs for m in e.values()), "all sent late are marked historical")
    times = [e["event/id"].timestamp / 1000 for e in evs]
    check(all(outage_start - 1 <= t <= outage_end + 1 for t in times), "each carries the time it happened, within the outage")
    check(times == sorted(times), "their times ascend")
    results = [e["event/code"].int_value for e in evs if e["event/kind"].string_value == "cycle_ended"]
    check(results.count(0) == 4 and results.count(10) == 1, f"cycle results: four homed, one aborted (code 10): {results}")
    alarms = [e for e in evs if e["event/kind"].string_value == "alarm_raised"]
    check(any(e["event/code"].int_value == 10 and "abort" in e["event/text"].string_value for e in alarms),
          "the abort alarm arrives with its code and text")
    check("alarms_reset" in kinds, "the reset arrives")
    settings = [e for e in evs if e["event/kind"].string_value == "setting_changed"]
    check(any(e["event/setting"].string_value == "axis.x.seek_feedrate" and e["event/new_value"].long_value == old_feed + 7
              and e["event/old_value"].long_value == old_feed for e in settings),
          "the settings change arrives with its name, old and new value")
    check(kinds.count("cycle_started") == 5, "every cycle's start arrives")
    durations = [e["event/duration_ms"].long_value for e in evs if e["event/kind"].string_value == "cycle_ended"]
    check(all(d > 0 for d in durations), f"cycle ends carry their duration: {durations}")
    seqs = [p.seq for t, p, _ in messages[seen_before:] if t in ("NBIRTH", "NDATA")]
    check(seqs and all((b - a) % 256 == 1 for a, b in zip(seqs, seqs[1:])), "seq continuous from the new birth")

    # Delivered events leave the outbox: a rebirth sends none again.
    n = len(events())
    ncmd(sub, "m1", "Node Control/Rebirth")
    births = len(of("NBIRTH"))
    check(wait_until(lambda: len(of("NBIRTH")) > births, 10), "rebirth")
    time.sleep(1.0)
    check(len(events()) == n, "delivered events are not sent again")

    # The primary host goes offline: the module dies (NDEATH with its birth's
    # bdSeq) and publishes nothing until the host is back; then a new birth
    # with the next bdSeq and what happened meanwhile, historical.
    bd = {m.name: m for m in of("NBIRTH")[-1].metrics}["bdSeq"].long_value
    deaths = len(of("NDEATH"))
    sub.publish(STATE, json.dumps({"online": False, "timestamp": int(time.time() * 1000)}), qos=1, retain=True)
    check(wait_until(lambda: len(of("NDEATH")) > deaths, 10), "host offline: the module publishes its NDEATH")
    if len(of("NDEATH")) > deaths:
        check({m.name: m for m in of("NDEATH")[-1].metrics}["bdSeq"].long_value == bd, "with its birth's bdSeq")
    quiet_from = len(messages)
    mb = modbus()
    check(home_and_wait(mb), "a cycle while the host is offline")
    mb.close()
    time.sleep(1.0)
    check(not [t for t, _, _ in messages[quiet_from:] if t in ("NBIRTH", "NDATA")], "nothing published while the host is offline")
    births = len(of("NBIRTH"))
    sub.publish(STATE, json.dumps({"online": True, "timestamp": int(time.time() * 1000)}), qos=1, retain=True)
    check(wait_until(lambda: len(of("NBIRTH")) > births, 15), "host online again: a new birth")
    if len(of("NBIRTH")) > births:
        check({m.name: m for m in of("NBIRTH")[-1].metrics}["bdSeq"].long_value == (bd + 1) % 256, "with the next bdSeq")
    check(wait_until(lambda: len(ended()) >= 6, 10), "the cycle run while the host was offline arrives after the new birth")
finally:
    shut_down([daemon], sub, broker)
if failures:
    print(open(os.path.join(work, "homingd.log")).read()[-3000:])
sys.exit(1 if failures else 0)
