#!/usr/bin/python3
"""The DISPLAY program of peer.ini: homes LinuxCNC's simulated joints from
given start positions and prints what each homing gave, then shuts LinuxCNC
down. No GUI and no X: it drives LinuxCNC through its Python modules
(linuxcnc: task commands and status; hal: the simulated machine's pins).

Started by the linuxcnc script as `peer_display.py -ini INI`. Reads:
  PEER_STARTS   a file with one start position (mm, machine frame) per line
  PEER_TIMEOUT  seconds one home-all may take (default 60)
Prints, one line per joint and start (the linuxcnc script's other output
goes to the same stdout, so every line of ours begins with "PEER "):
  PEER START n=4 trip=-10 hysteresis=0.05 period=0.001
  PEER JOINT j=0 search=-20 latch=1 final=20 home=1 edge=release edge_mm=-9.95
  PEER RESULT j=0 start=12.3 error_mm=... cycle_s=... rest_mm=...
  PEER FAIL start=12.3 reason=...
  PEER DONE results=N failed=M
Run by bench/linuxcnc/run_peer.sh.

The error of a homing: once homed, LinuxCNC takes the carriage to stand at
joint coordinate pos-fb, where HOME_OFFSET (0) is the edge it latched; the
carriage really stands (carriage - true edge) from the true edge. error =
pos-fb - HOME_OFFSET - (carriage - true edge): positive when LinuxCNC puts
the carriage further positive than it is.
"""
import os
import sys
import time

import hal
import linuxcnc


def say(line):
    print("PEER " + line, flush=True)


def ini_path():
    args = sys.argv[1:]
    if "-ini" in args:
        return args[args.index("-ini") + 1]
    sys.exit("peer_display.py: no -ini argument")


def wait_for(predicate, timeout, what, poll=0.002):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if predicate():
            return True
        time.sleep(poll)
    raise TimeoutError(what)


def main():
    inifile = linuxcnc.ini(ini_path())
    joints = int(inifile.find("KINS", "JOINTS"))
    trip = float(inifile.find("PEER", "SWITCH_TRIP"))
    hysteresis = float(inifile.find("PEER", "SWITCH_HYSTERESIS"))
    period = float(inifile.find("EMCMOT", "SERVO_PERIOD")) / 1e9
    timeout = float(os.environ.get("PEER_TIMEOUT", "60"))
    with open(os.environ["PEER_STARTS"]) as f:
        starts = [float(x) for x in f.read().split()]

    cfg = []
    for j in range(joints):
        sec = f"JOINT_{j}"
        search = float(inifile.find(sec, "HOME_SEARCH_VEL"))
        latch = float(inifile.find(sec, "HOME_LATCH_VEL"))
        # homing.c: same signs latch the rising edge on a re-approach, opposite
        # signs the falling edge moving off the switch. sim_home_switch (switch
        # on the negative side) trips at home-pos and releases hysteresis above.
        same = search * latch > 0
        edge_mm = trip if same else trip + hysteresis
        c = {"search": search, "latch": latch, "final": float(inifile.find(sec, "HOME_FINAL_VEL") or 0),
             "home": float(inifile.find(sec, "HOME") or 0), "home_offset": float(inifile.find(sec, "HOME_OFFSET") or 0),
             "edge": "trip" if same else "release", "edge_mm": edge_mm}
        cfg.append(c)
        say(f"JOINT j={j} search={search:g} latch={latch:g} final={c['final']:g} home={c['home']:g} "
            f"edge={c['edge']} edge_mm={edge_mm:g}")
    say(f"START n={len(starts)} joints={joints} trip={trip:g} hysteresis={hysteresis:g} period={period:g}")

    # The hal module reads and sets pins only from a component of its own.
    comp = hal.component("peer-display")
    comp.ready()
    s = linuxcnc.stat()
    cmd = linuxcnc.command()
    err = linuxcnc.error_channel()

    def poll():
        s.poll()
        e = err.poll()
        if e:
            say(f"MESSAGE kind={e[0]} text={e[1]!r}")
        return s

    # Task is up once the display starts; wait for its status to be served.
    def task_ready():
        try:
            poll()
            return True
        except linuxcnc.error:
            return False
    wait_for(task_ready, 30, "task status")
    cmd.state(linuxcnc.STATE_ESTOP_RESET)
    cmd.wait_complete()
    cmd.state(linuxcnc.STATE_ON)
    cmd.wait_complete()
    cmd.mode(linuxcnc.MODE_MANUAL)
    cmd.wait_complete()
    cmd.teleop_enable(0)  # joint mode: homing is per joint
    cmd.wait_complete()
    wait_for(lambda: poll().task_state == linuxcnc.STATE_ON, 10, "machine on")

    results = failed = 0
    for start in starts:
        poll()
        if any(s.homed[j] for j in range(joints)):
            # Task turns teleop on once every joint is homed; unhoming is
            # refused outside joint mode.
            cmd.teleop_enable(0)
            cmd.wait_complete()
            wait_for(lambda: poll().motion_mode == linuxcnc.TRAJ_MODE_FREE, 10, "joint mode")
            cmd.unhome(-1)
            cmd.wait_complete()
            wait_for(lambda: not any(poll().homed[j] for j in range(joints)), 10, "unhome")
        # Place every carriage at the start (the joints stand still, unhomed).
        for j in range(joints):
            hal.set_p(f"sum2.{j}.in1", repr(start - hal.get_value(f"joint.{j}.motor-pos-cmd")))
        time.sleep(0.02)  # a few periods: the switches see the new places
        if any(hal.get_value(f"sim-home-switch.{j}.home-sw") for j in range(joints)) and start > trip:
            say(f"FAIL start={start!r} reason=switch_active_after_placing")
            failed += 1
            continue
        t0 = [hal.get_value(f"integ.{j}.out") for j in range(joints)]
        cmd.home(-1)
        cmd.wait_complete()
        try:
            wait_for(lambda: all(poll().homed[j] for j in range(joints)) and not any(
                hal.get_value(f"joint.{j}.homing") for j in range(joints)), timeout, "home all")
        except TimeoutError:
            say(f"FAIL start={start!r} reason=timeout homed={list(s.homed[:joints])}")
            failed += 1
            cmd.abort()
            cmd.wait_complete()
            continue
        for j in range(joints):
            c = cfg[j]
            pos_fb = hal.get_value(f"joint.{j}.pos-fb")
            carriage = hal.get_value(f"sum2.{j}.out")
            cycle = hal.get_value(f"integ.{j}.out") - t0[j]
            error = pos_fb - c["home_offset"] - (carriage - c["edge_mm"])
            say(f"RESULT j={j} start={start!r} error_mm={error!r} cycle_s={cycle!r} rest_mm={carriage!r} "
                f"pos_fb={pos_fb!r}")
            results += 1
    say(f"DONE results={results} failed={failed}")
    cmd.state(linuxcnc.STATE_OFF)
    cmd.wait_complete()
    cmd.state(linuxcnc.STATE_ESTOP)
    cmd.wait_complete()
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except Exception as e:  # noqa: BLE001  (the run must end, and say why)
        say(f"ERROR {type(e).__name__}: {e}")
        sys.exit(1)
