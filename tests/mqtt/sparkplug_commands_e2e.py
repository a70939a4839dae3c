#!/usr/bin/python3
"""End-to-end: commands over MQTT (NCMD). Off by default: refused and answered
as an event. With --mqtt-commands: cmd/home_all homes the machine; refused for
the same reason as the same command over Modbus when homing is blocked; held
commands (jog) and settings are never taken. Debian's mosquitto on loopback,
an independent Sparkplug host (paho-mqtt, python3-protobuf), pymodbus.

usage: sparkplug_commands_e2e.py HOMINGD PYTHON_DIR"""
import os, sys, tempfile

from pymodbus.client import ModbusTcpClient

import e2e_support
from e2e_support import (Broker, alias_names, check, failures, free_port, import_sparkplug, shut_down,
                         sparkplug_host, start_homingd, wait_until)
from e2e_support import input_register as ir

homingd, pydir = sys.argv[1], sys.argv[2]
import_sparkplug(pydir)

work = tempfile.mkdtemp(prefix="mqtt-cmd-e2e-")
broker = Broker(work)

messages = []
sub = sparkplug_host("cmd-e2e-host", broker, lambda kind, node, p, _msg: messages.append((kind, node, p)))

def start(node, *extra):
    port = free_port()
    p = start_homingd(homingd, port, os.path.join(work, node + ".db"), broker.url(), node, *extra,
                      log=open(os.path.join(work, node + ".log"), "w"))
    return p, port

def births(node): return [p for t, n, p in messages if t == "NBIRTH" and n == node]
def aliases(node): return alias_names(births(node)[0])
def answers(node):
    """The command events of a node: (setting, command result, refusal reason, text)."""
    names = aliases(node)
    out = []
    for t, n, p in messages:
        if t != "NDATA" or n != node: continue
        ev = {names.get(m.alias): m for m in p.metrics}
        if "event/kind" in ev and ev["event/kind"].string_value == "command":
            out.append((ev["event/setting"].string_value, ev["event/code"].int_value,
                        ev["event/new_value"].long_value if "event/new_value" in ev else 0, ev["event/text"].string_value))
    return out

def ncmd(node, name, value=True, retain=False): return e2e_support.ncmd(sub, node, name, value, retain)

daemons = []
try:
    off, off_port = start("off"); daemons.append(off)
    on, on_port = start("on", "--mqtt-commands"); daemons.append(on)
    check(wait_until(lambda: births("off") and births("on"), 15), "both modules are born")

    # Off by default: refused, answered, nothing moves.
    ncmd("off", "cmd/home_all")
    check(wait_until(lambda: len(answers("off")) >= 1, 10), "a command to a module without --mqtt-commands is answered")
    if answers("off"):
        name, _, reason, text = answers("off")[0]
        check(name == "cmd.home_all" and reason != 0 and "--mqtt-commands" in text, f"as refused, naming the option: {text}")
    mb_off = ModbusTcpClient("127.0.0.1", port=off_port, timeout=2, retries=0); mb_off.connect()
    # The answer came after the NCMD was handled; a cmd.reset_alarm over Modbus
    # behind it is judged no earlier than anything the NCMD handed the loop, so
    # once it is judged a home_all carried out would show (state, one more count).
    count = ir(mb_off, 11)  # status.command_count
    mb_off.write_coil(2, True, slave=1)  # cmd.reset_alarm
    check(wait_until(lambda: ir(mb_off, 11) != count, 10), "a reset over Modbus behind it is judged")
    check(ir(mb_off, 1) == 0 and ir(mb_off, 11) == (count + 1) % 65536,
          "and nothing homes (state not_homed, only the reset judged)")

    # On: home_all homes.
    ncmd("on", "cmd/home_all")
    mb = ModbusTcpClient("127.0.0.1", port=on_port, timeout=2, retries=0)
    check(wait_until(lambda: mb.connect(), 5), "Modbus connects")
    check(wait_until(lambda: ir(mb, 1) == 2, 30), "cmd/home_all over MQTT homes the machine (state homed)")
    check(wait_until(lambda: any(a[0] == "cmd.home_all" and a[1] == 1 and a[2] == 0 for a in answers("on")), 5),
          "and is answered as accepted (command result 1)")

    # Homing blocked by a latched alarm: the same refusal as over Modbus.
    # The simulator's e-stop pressed and released: the alarm stays latched. A
    # simulator write is answered once the loop shows it.
    r = mb.write_coil(0, True, slave=247)  # sim.estop
    wait_until(lambda: ir(mb, 1) == 3, 10)
    r2 = mb.write_coil(0, False, slave=247)
    check(not r.isError() and not r2.isError(), f"the simulator's e-stop is pressed and released: {r}, {r2}")
    check(wait_until(lambda: ir(mb, 1) == 3, 10), "an alarm is latched")
    n = len(answers("on"))
    ncmd("on", "cmd/home_all")
    check(wait_until(lambda: len(answers("on")) > n, 10), "cmd/home_all during the alarm is answered")
    answer = answers("on")[-1] if len(answers("on")) > n else None
    count = ir(mb, 11)  # status.command_count: the result below is this command's once it moved
    r = mb.write_coil(0, True, slave=1)
    check(wait_until(lambda: ir(mb, 11) != count, 10), "the same command over Modbus is judged")
    modbus_result = ir(mb, 6)  # status.last_command_result
    check(not r.isError() and modbus_result == 3, f"over Modbus the same command is refused_alarm (3): {modbus_result}")
    check(answer is not None and answer[1] == modbus_result and "refused_alarm" in answer[3],
          f"and over MQTT for the same reason: {answer}")

    # Never over MQTT: held commands and settings. The setting goes first: the
    # broker delivers one topic's messages in order, so once the jog is
    # answered the setting has been handled.
    n = len(answers("on"))
    ncmd("on", "axis/x/seek_feedrate")
    ncmd("on", "cmd/jog_plus/x")
    check(wait_until(lambda: len(answers("on")) >= n + 1, 10), "a jog over MQTT is answered")
    check(all(reason != 0 for _, _, reason, _ in answers("on")[n:]), "and refused")
    feed = mb.read_holding_registers(102, 1, slave=1).registers[0]
    check(feed == 1000, "no setting was written over MQTT")
    mb.close(); mb_off.close()

    # A retained NCMD (forbidden by Sparkplug B, replayed by the broker at
    # every subscription) is ignored and logged: a module started, or
    # reconnected, after it does not home.
    ncmd("ret", "cmd/home_all", retain=True).wait_for_publish(5)
    ret, ret_port = start("ret", "--mqtt-commands"); daemons.append(ret)
    check(wait_until(lambda: births("ret"), 15), "the module started after a retained NCMD is born")
    mb_ret = ModbusTcpClient("127.0.0.1", port=ret_port, timeout=2, retries=0)
    check(wait_until(lambda: mb_ret.connect(), 5), "Modbus connects")
    retained_logged = lambda: "retained on the broker" in open(os.path.join(work, "ret.log")).read()
    check(wait_until(retained_logged, 10), "the retained NCMD is logged as ignored")
    check(ir(mb_ret, 1) == 0 and ir(mb_ret, 11) == 0, "and nothing was carried out (not_homed, no command judged)")
    check(not any(a[0] == "cmd.home_all" for a in answers("ret")), "nor answered as a command")
    mb_ret.close()
    sub.publish("spBv1.0/plant/NCMD/ret", b"", qos=1, retain=True).wait_for_publish(5)  # cleared

    # A host flooding refused or unreadable NCMDs: every command is still
    # answered as an event, the log has the first of each reason whole and
    # then one count per interval (--refusal-log-interval-s), never a line each.
    flood, _ = start("flood", "--refusal-log-interval-s", "1"); daemons.append(flood)
    check(wait_until(lambda: births("flood"), 15), "the flooded module is born")
    for _ in range(20):
        ncmd("flood", "cmd/home_all")
    for _ in range(10):
        sub.publish("spBv1.0/plant/NCMD/flood", b"not protobuf \xff\xff", qos=0)
    check(wait_until(lambda: len(answers("flood")) >= 20, 15), f"all 20 commands are answered: {len(answers('flood'))}")
    flood_log = lambda: open(os.path.join(work, "flood.log")).read()
    counted = lambda: "more NCMDs refused, cmd/home_all refused" in flood_log() and \
        "more NCMDs refused, not a Sparkplug B payload" in flood_log()
    check(wait_until(counted, 10), "the repeats are counted per reason")
    log = flood_log()
    check(log.count("commands over MQTT are off") == 1, f"one whole line for the refused commands: {log.count('commands over MQTT are off')}")
    check(log.count("is not a Sparkplug B payload") == 1, "one whole line for the unreadable payloads")
finally:
    shut_down(daemons, sub, broker)
if failures:
    for node in ("off", "on"):
        print(f"--- {node} ---\n" + open(os.path.join(work, node + ".log")).read()[-2500:])
sys.exit(1 if failures else 0)
