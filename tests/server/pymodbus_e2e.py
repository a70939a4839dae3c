#!/usr/bin/python3
"""End-to-end test of the real homingd with pymodbus 3.0 (Debian's
python3-pymodbus; run with /usr/bin/python3), a client independent of
libmodbus. Addresses come from hmi_maps/registers.csv and sim_registers.csv.

Starts homingd on a free 127.0.0.1 port with a temporary database, configures
axes, runs a home-all (default sequence: Z, then X+Y), checks positions
against the simulator unit's truth, and checks device identification
(FC 43/14), an unknown unit (0x0B), an unknown function (01), quantity (03),
half of a 32-bit value (02), all-or-nothing FC 16 and exception 06 during a
cycle, and reads Z's homing trace with function 20 (read file record; layout
in hmi_maps/README.md). Exits non-zero on the first failure. Every wait is bounded.
"""
import argparse
import csv
import os
import socket
import sys
import tempfile
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from homingd_py import Daemon, check, failures  # noqa: E402  (also stubs serial_asyncio)

try:
    from pymodbus.client import ModbusTcpClient
    from pymodbus.file_message import FileRecord, ReadFileRecordRequest
    from pymodbus.mei_message import ReadDeviceInformationRequest
    from pymodbus.pdu import ExceptionResponse
except ImportError as e:  # a missing tool fails the test, never skips it
    print(f"FAIL: pymodbus is not importable ({e}); run tools/install-deps.sh", file=sys.stderr)
    sys.exit(1)

MODULE, SIM = 1, 247


class Map:
    def __init__(self, *paths):
        self.rows = {}
        for path in paths:
            with open(path, newline="") as f:
                for row in csv.DictReader(f):
                    self.rows[row["name"]] = row

    def __getitem__(self, name):
        return self.rows[name]


def is_exception(rsp, code=None):
    if not isinstance(rsp, ExceptionResponse):
        return False
    return code is None or rsp.exception_code == code


class Regs:
    def __init__(self, client, rows):
        self.c = client
        self.m = rows

    def unit(self, row):
        return SIM if row["name"].startswith("sim.") else MODULE

    def read(self, name):
        row = self.m[name]
        a, words, table = int(row["address"]), int(row["words"]), row["table"]
        u = self.unit(row)
        if table == "coil":
            r = self.c.read_coils(a, 1, slave=u)
            return int(r.bits[0])
        if table == "discrete_input":
            r = self.c.read_discrete_inputs(a, 1, slave=u)
            return int(r.bits[0])
        if table == "holding_register":
            r = self.c.read_holding_registers(a, words, slave=u)
        else:
            r = self.c.read_input_registers(a, words, slave=u)
        if r.isError():
            raise RuntimeError(f"read {name}: {r}")
        w = r.registers
        if words == 1:
            v = w[0]
            return v - 65536 if row["type"] == "i16" and v >= 32768 else v
        v = (w[0] << 16) | w[1]  # high word first
        return v - (1 << 32) if row["type"] == "i32" and v >= (1 << 31) else v

    def words(self, name, raw):
        row = self.m[name]
        if int(row["words"]) == 1:
            return [raw & 0xFFFF]
        u = raw & 0xFFFFFFFF
        return [u >> 16, u & 0xFFFF]

    def write(self, name, raw):
        row = self.m[name]
        a, u = int(row["address"]), self.unit(row)
        if row["table"] == "coil":
            return self.c.write_coil(a, bool(raw), slave=u)
        return self.c.write_registers(a, self.words(name, raw), slave=u)

    def mm(self, name):
        return self.read(name) / 1000.0

    def holding_snapshot(self):
        return {n: self.read(n) for n, r in self.m.rows.items()
                if r["table"] == "holding_register" and not n.startswith("sim.")}


def wait_for(pred, timeout, every=0.01):
    deadline = time.monotonic() + timeout
    while True:
        if pred():
            return True
        if time.monotonic() > deadline:
            return False
        time.sleep(every)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--homingd", required=True)
    ap.add_argument("--map", required=True)
    ap.add_argument("--sim-map", required=True)
    ap.add_argument("--version", required=True, help="the build's version (CMake project version)")
    args = ap.parse_args()
    rows = Map(args.map, args.sim_map)

    with tempfile.TemporaryDirectory(prefix="homingd-py-") as tmp:
        d = Daemon(args.homingd, os.path.join(tmp, "settings.db"))
        try:
            run(d, rows, args.version)
        finally:
            d.finish()
    if failures:
        print(f"{len(failures)} failure(s)", file=sys.stderr)
        return 1
    return 0


def run(d, rows, version):
    c = ModbusTcpClient("127.0.0.1", port=d.port, timeout=2, retries=0)
    if not check(c.connect(), "connected"):
        return
    r = Regs(c, rows)
    check(r.read("status.map_version") == 1, "status.map_version == 1")

    # Device identification (FC 43/14): our identity.
    req = ReadDeviceInformationRequest(read_code=0x01, object_id=0x00)
    req.unit_id = MODULE   # pymodbus 3.0 (the constructor's keyword is `unit` there, `slave` later)
    req.slave_id = MODULE
    rsp = c.execute(req)
    info = getattr(rsp, "information", {}) if not rsp.isError() else {}
    texts = {k: (v.decode() if isinstance(v, bytes) else str(v)) for k, v in info.items()}
    check(len(texts) == 3 and all(texts.values()), f"device identification basic objects: {texts}")
    check(texts.get(2) == version, "revision " + version)
    check(not any("libmodbus" in t for t in texts.values()), "identity is ours, not libmodbus's")

    # Unknown unit: 0x0B; unknown function: 01 (raw over a socket); quantity: 03.
    rsp = c.read_input_registers(0, 1, slave=9)
    check(is_exception(rsp, 0x0B), f"unit 9 -> exception 0B ({rsp})")
    s = socket.create_connection(("127.0.0.1", d.port), timeout=2)
    s.sendall(bytes([0, 1, 0, 0, 0, 2, MODULE, 0x41]))
    reply = s.recv(64)
    s.close()
    check(reply[7:] == bytes([0xC1, 0x01]), f"FC 0x41 -> exception 01 ({reply.hex()})")
    check(is_exception(c.read_holding_registers(100, 126, slave=MODULE), 3), "126 registers -> 03")
    check(is_exception(c.read_coils(0, 2001, slave=MODULE), 3), "2001 coils -> 03")

    before = r.holding_snapshot()
    pull = int(rows["axis.x.pull_off"]["address"])
    check(is_exception(c.write_register(pull, 1, slave=MODULE), 2), "FC 6 on half of a 32-bit value -> 02")
    mode = int(rows["axis.x.mode"]["address"])
    block = c.read_holding_registers(mode, 6, slave=MODULE).registers
    bad = list(block)
    bad[1] = 1     # direction: fine
    bad[5] = 5000  # debounce_ms: out of range
    check(is_exception(c.write_registers(mode, bad, slave=MODULE), 3), "FC 16 with one bad value -> 03")
    # pymodbus frames what libmodbus refuses to: 124 registers in one request
    # (a frame longer than the standard's). Refused with 03, the connection kept.
    check(is_exception(c.write_registers(mode, [1] * 124, slave=MODULE), 3), "FC 16 of 124 registers -> 03")
    check(is_exception(c.write_coils(0, [True] * 2000, slave=MODULE), 3), "FC 15 of 2000 coils -> 03")
    check(r.holding_snapshot() == before, "nothing changed after refused writes")

    # Configure over Modbus.
    for name, raw in (("axis.x.pull_off", 1800), ("axis.y.home_position", 25000),
                      ("axis.z.pull_off", 1200), ("axis.z.home_position", -3000)):
        check(not r.write(name, raw).isError(), f"write {name} = {raw}")
        check(r.read(name) == raw, f"read back {name}")

    # Home all, watching phases; exception 06 on a settings write during it.
    check(not r.write("cmd.home_all", 1).isError(), "cmd.home_all")
    saw = {"z_alone": False, "xy": False, "busy06": False}
    deadline = time.monotonic() + 20
    state = None
    while time.monotonic() < deadline:
        state = r.read("status.state")
        z1, x, y, z2 = (r.read("axis.z.phase"), r.read("axis.x.phase"), r.read("axis.y.phase"),
                        r.read("axis.z.phase"))
        if z1 == 3 and z2 == 3:
            saw["z_alone"] = saw["z_alone"] or (x == 1 and y == 1)
            if not saw["busy06"]:
                rsp = r.write("axis.x.pull_off", 999)
                saw["busy06"] = is_exception(rsp, 6)
        if x in range(2, 13) or y in range(2, 13):
            saw["xy"] = True
            if z2 != 13:
                check(False, f"X/Y moved before Z was done (z={z2})")
        if state in (2, 3):
            break
        time.sleep(0.003)
    check(state == 2, f"homed (state {state})")
    check(saw["z_alone"], "Z sought alone while X and Y waited (step 1)")
    check(saw["xy"], "X and Y moved in step 2")
    check(saw["busy06"], "settings write during the cycle -> 06")
    check(r.read("axis.x.pull_off") == 1800, "the refused write changed nothing")
    for a in "xyz":
        check(r.read(f"axis.{a}.homed") == 1, f"axis.{a}.homed")
        check(r.read(f"axis.{a}.position") == r.read(f"axis.{a}.home_position"),
              f"axis.{a}.position == home_position")
        expected = r.mm(f"sim.{a}.sensor_max") + r.mm(f"sim.{a}.hysteresis") + r.mm(f"axis.{a}.pull_off")
        actual = r.mm(f"sim.{a}.actual_position")
        check(abs(actual - expected) < 0.02, f"sim.{a}.actual_position {actual:.4f} ~ {expected:.4f}")
    check(r.read("status.homing_cycles") == 1, "status.homing_cycles == 1")
    check_trace(c, r)
    c.close()


def read_file_words(c, file_number, first, count):
    req = ReadFileRecordRequest(records=[FileRecord(file_number=file_number, record_number=first,
                                                    record_length=count)])
    req.unit_id = MODULE   # pymodbus 3.0's name; later versions call it slave_id
    req.slave_id = MODULE
    rsp = c.execute(req)
    if rsp.isError() or len(rsp.records) != 1:
        return None
    data = rsp.records[0].record_data
    return [int.from_bytes(data[i:i + 2], "big") for i in range(0, len(data), 2)]


def s32(hi, lo):
    v = hi << 16 | lo
    return v - (1 << 32) if v & 0x80000000 else v


# Z's trace of the cycle just run: function 20, file 3, 10 header words then
# 8 words per control period (time ms, phase, position um, velocity um/s, sensor).
def check_trace(c, r):
    head = read_file_words(c, 3, 0, 10)
    if not check(head is not None and len(head) == 10, f"FC 20 header of Z ({head})"):
        return
    count = head[0]
    words = []
    for first in range(0, 8 * count, 120):
        chunk = read_file_words(c, 3, 10 + first, min(120, 8 * count - first))
        if chunk is None:
            check(False, f"FC 20 records {10 + first}.. of Z")
            return
        words += chunk
    samples = [(words[i] << 16 | words[i + 1], words[i + 2], s32(words[i + 3], words[i + 4]),
                s32(words[i + 5], words[i + 6]), words[i + 7]) for i in range(0, len(words), 8)]
    check(count > 10 and len(samples) == count, f"Z trace has {count} samples")
    check(head[6] == 0, "Z trace: no alarm")
    times = [t for t, *_ in samples]
    check(times[0] == 0 and times == sorted(times), "Z trace: times from 0, in order")
    position = r.read("axis.z.position")
    check(abs(samples[-1][2] - position) <= 1, f"Z trace ends at axis.z.position ({samples[-1][2]} vs {position})")
    seek = [v for _, phase, _, v, _ in samples if phase == 3]
    fastest = -r.read("axis.z.seek_feedrate") * 1000 / 60
    check(seek and abs(min(seek) - fastest) <= 2, f"Z sought at seek_feedrate ({min(seek or [0])} um/s)")
    check(any(sensor for *_, sensor in samples) and samples[-1][4] == 0, "Z trace: sensor on, then off")
    edge = s32(head[4], head[5])
    check(s32(head[2], head[3]) != -1 and abs(edge - (position - r.read("axis.z.pull_off"))) <= 1,
          f"Z reference edge {edge} um is pull_off below the rest point")


if __name__ == "__main__":
    sys.exit(main())
