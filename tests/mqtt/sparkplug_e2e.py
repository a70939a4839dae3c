#!/usr/bin/python3
"""End-to-end: homingd --mqtt against Debian's mosquitto on loopback, watched by
an independent Sparkplug subscriber (paho-mqtt, payloads decoded by
python3-protobuf from the project's sparkplug_b.proto).

usage: sparkplug_e2e.py HOMINGD PYTHON_DIR"""
import os, signal, sys, tempfile

from pymodbus.client import ModbusTcpClient

from e2e_support import (Broker, check, check_daemon_logs, failures, free_port, import_sparkplug, ncmd, sparkplug_host,
                         start_homingd, wait_until)

homingd, pydir = sys.argv[1], sys.argv[2]
spb = import_sparkplug(pydir)

work = tempfile.mkdtemp(prefix="mqtt-e2e-")
broker = Broker(work)
modbus_port = free_port()

messages = []  # (type, Payload)
sub = sparkplug_host("e2e-host", broker, lambda kind, _node, p, _msg: messages.append((kind, p)))

def of(kind): return [p for t, p in messages if t == kind]
daemon = start_homingd(homingd, modbus_port, os.path.join(work, "h.db"), broker.url(), "m1")
try:
    check(wait_until(lambda: len(of("NBIRTH")) == 1), "NBIRTH arrives")
    birth = of("NBIRTH")[0]
    names = {m.name: m for m in birth.metrics}
    check(birth.seq == 0, "birth has seq 0")
    check("bdSeq" in names and names["bdSeq"].datatype == spb.Int64, "birth carries bdSeq as Int64")
    check(names.get("Node Control/Rebirth") is not None and names["Node Control/Rebirth"].datatype == spb.Boolean,
          "birth carries Node Control/Rebirth")
    csv = open(os.path.join(os.path.dirname(__file__), "..", "..", "hmi_maps", "registers.csv")).read().splitlines()
    expected = {}
    for line in csv[1:]:
        c = line.split(",")
        if c[1] in ("input_register", "discrete_input"):
            expected[c[0].replace(".", "/")] = c[4]
    expected.pop("status/heartbeat", None)  # left out on purpose (keep-alive and NDEATH say the module is alive)
    missing = [n for n in expected if n not in names]
    check(not missing, f"birth has every input register and discrete input ({len(expected)}), missing {missing[:5]}")
    typemap = {"bool": spb.Boolean, "u16": spb.UInt16, "i16": spb.Int16, "u32": spb.UInt32, "i32": spb.Int32,
               "enum": spb.UInt16, "bitmask": spb.UInt16}
    wrong = [n for n, t in expected.items() if n in names and names[n].datatype not in (typemap[t], spb.Double)]
    check(not wrong, f"datatypes follow the register types, wrong: {wrong[:5]}")
    check(all(m.HasField("alias") for n, m in names.items() if n in expected), "every metric has an alias")
    pos = names["axis/x/position"]
    check(pos.datatype == spb.Double, "positions are Double (mm)")

    # Homing all axes: data by exception, seq continuing from the birth.
    mb = ModbusTcpClient("127.0.0.1", port=modbus_port, timeout=2, retries=0)
    check(wait_until(lambda: mb.connect(), 5), "Modbus connects")
    before = len(of("NDATA"))
    mb.write_coil(0, True, slave=1)  # cmd.home_all
    homed_aliases = {names[f"axis/{a}/homed"].alias for a in "xyz"}
    def homed_seen():
        return any(m.alias in homed_aliases and m.boolean_value for p in of("NDATA") for m in p.metrics)
    check(wait_until(homed_seen, 60), "NDATA reports axes homed during the cycle")
    data = of("NDATA")
    check(len(data) > before, "NDATA published during homing")
    check(all(not m.name for p in data for m in p.metrics), "NDATA uses aliases, no names")
    seqs = [p.seq for t, p in messages if t in ("NBIRTH", "NDATA")]
    check(all((b - a) % 256 == 1 for a, b in zip(seqs, seqs[1:])), f"seq continuous from the birth: {seqs[:10]}...")

    # An alarm's text beside its code: the simulator's e-stop pressed at rest
    # latches the machine's alarm; its text arrives as a String, and is
    # cleared once the e-stop is released and the alarm reset.
    check(names.get("status/global_alarm_text") is not None and names["status/global_alarm_text"].datatype == spb.String,
          "birth carries status/global_alarm_text as String")
    check(all(names.get(f"axis/{a}/alarm_text") is not None for a in "xyzabc"), "birth carries axis/<a>/alarm_text")
    text_alias = names["status/global_alarm_text"].alias
    def texts(): return [m.string_value for p in of("NDATA") for m in p.metrics if m.alias == text_alias]
    check(not mb.write_coil(0, True, slave=247).isError(), "sim.estop pressed")  # sim.estop
    check(wait_until(lambda: any(t.startswith("emergency stop pressed; ") for t in texts()), 10),
          f"the e-stop's text arrives in status/global_alarm_text: {texts()[-1:]}")
    check(not mb.write_coil(0, False, slave=247).isError(), "sim.estop released")
    mb.write_coil(2, True, slave=1)  # cmd.reset_alarm
    check(wait_until(lambda: texts() and texts()[-1] == "", 10), "the text is cleared after the reset")

    # Rebirth on command.
    ncmd(sub, "m1", "Node Control/Rebirth")
    check(wait_until(lambda: len(of("NBIRTH")) == 2), "rebirth answered with a new NBIRTH")
    check(of("NBIRTH")[1].seq == 0, "the new birth restarts seq at 0")
    bd = names["bdSeq"].long_value
    daemon.send_signal(signal.SIGKILL); daemon.wait()
    check(wait_until(lambda: len(of("NDEATH")) >= 1, 15), "NDEATH (the Will) arrives after SIGKILL")
    if of("NDEATH"):
        death = {m.name: m for m in of("NDEATH")[0].metrics}
        check(death.get("bdSeq") is not None and death["bdSeq"].long_value == bd, "NDEATH carries the birth's bdSeq")

    # Started again on the same files after that power cut, and again after a
    # clean stop: each session takes the next bdSeq, never one a death
    # certificate already named (it started at 0 on every start).
    def last_bd(kind): return {m.name: m for m in of(kind)[-1].metrics}["bdSeq"].long_value
    for restart, expected in ((1, (bd + 1) % 256), (2, (bd + 2) % 256)):
        births = len(of("NBIRTH"))
        daemon = start_homingd(homingd, modbus_port, os.path.join(work, "h.db"), broker.url(), "m1")
        check(wait_until(lambda: len(of("NBIRTH")) > births, 15), f"born again after restart {restart}")
        if len(of("NBIRTH")) > births:
            check(last_bd("NBIRTH") == expected, f"restart {restart}: bdSeq {last_bd('NBIRTH')}, expected {expected}")
        deaths = len(of("NDEATH"))
        daemon.send_signal(signal.SIGTERM); daemon.wait()
        check(wait_until(lambda: len(of("NDEATH")) > deaths, 10), f"restart {restart}: a clean stop publishes NDEATH")
        if len(of("NDEATH")) > deaths:
            check(last_bd("NDEATH") == expected, f"restart {restart}: the NDEATH names its session's bdSeq")
finally:
    if daemon.poll() is None:
        daemon.send_signal(signal.SIGKILL); daemon.wait()
    check_daemon_logs()
    sub.loop_stop()
    broker.stop()
sys.exit(1 if failures else 0)
