#!/usr/bin/python3
"""Checks the generated HMI files against the documented formats of the
products that import them (run by ctest under Debian's /usr/bin/python3).

  check_hmi_formats.py home-assistant hmi_maps/home_assistant_modbus.yaml hmi_maps/registers.json
  check_hmi_formats.py kepware hmi_maps/kepware_module.csv hmi_maps/registers.json module

Home Assistant: the keys and values its `modbus:` schema accepts
(homeassistant/components/modbus/__init__.py, validators.py), no scan_interval
below the 5 s it warns about, no duplicate entity name or address, and every
switch verifying by reading its coil back so a command falls back to "off".
Kepware: the 17 columns of a KEPServerEX tag export, plain ASCII (no mojibake
when read in a Windows code page), dotted tag names that become tag groups.
"""
import csv
import json
import re
import sys

import yaml

COMMON = {"name", "address", "slave", "device_address", "scan_interval", "unique_id"}
ALLOWED = {
    "sensors": COMMON | {"input_type", "data_type", "scale", "offset", "precision",
                         "unit_of_measurement", "swap", "count", "device_class", "state_class"},
    "binary_sensors": COMMON | {"input_type", "device_class", "slave_count"},
    "switches": COMMON | {"write_type", "command_on", "command_off", "verify", "device_class"},
}
INPUT_TYPES = {
    "sensors": {"holding", "input"},
    "binary_sensors": {"coil", "discrete_input", "holding", "input"},
}
DATA_TYPES = {"int16", "int32", "uint16", "uint32", "float32", "int64", "uint64", "float64", "string", "custom"}
VERIFY_KEYS = {"address", "input_type", "delay", "state_on", "state_off"}

failures = []


def fail(msg):
    failures.append(msg)


def check_home_assistant(path, registers_json):
    with open(path, encoding="utf-8") as f:
        doc = yaml.safe_load(f)
    hubs = doc.get("modbus")
    if not isinstance(hubs, list) or len(hubs) != 1:
        fail("modbus: must be a list with one hub")
        return
    hub = hubs[0]
    for key in ("name", "type", "host", "port"):
        if key not in hub:
            fail(f"hub lacks {key}")
    names, addresses = set(), set()
    counts = {}
    for platform, allowed in ALLOWED.items():
        entities = hub.get(platform, [])
        counts[platform] = len(entities)
        for e in entities:
            where = f"{platform}/{e.get('name')}"
            unknown = set(e) - allowed
            if unknown:
                fail(f"{where}: keys the integration does not accept: {sorted(unknown)}")
            for key in ("name", "address"):
                if key not in e:
                    fail(f"{where}: lacks {key}")
            if e.get("name") in names:
                fail(f"{where}: duplicate entity name")
            names.add(e.get("name"))
            scan = e.get("scan_interval", 15)
            if not isinstance(scan, int) or 0 < scan < 5:
                fail(f"{where}: scan_interval {scan} (Home Assistant warns below 5 s)")
            kind = e.get("input_type", e.get("write_type"))
            addr = (platform, kind, e.get("slave", 0), e.get("address"))
            if addr in addresses:
                fail(f"{where}: duplicate address {addr}")
            addresses.add(addr)
            if platform in INPUT_TYPES and e.get("input_type") not in INPUT_TYPES[platform]:
                fail(f"{where}: input_type {e.get('input_type')}")
            if platform == "sensors":
                if e.get("data_type") not in DATA_TYPES:
                    fail(f"{where}: data_type {e.get('data_type')}")
                if e.get("input_type") == "holding" and scan < 30:
                    fail(f"{where}: a setting polled every {scan} s (settings rarely change)")
            if platform == "switches":
                if e.get("write_type") != "coil":
                    fail(f"{where}: write_type {e.get('write_type')}")
                v = e.get("verify")
                if not isinstance(v, dict):
                    fail(f"{where}: no verify, the switch would stay on after a command")
                    continue
                if set(v) - VERIFY_KEYS:
                    fail(f"{where}: verify keys {sorted(set(v) - VERIFY_KEYS)}")
                if v.get("input_type") != "coil" or v.get("address", e.get("address")) != e.get("address"):
                    fail(f"{where}: verify must read its own coil back")
                if v.get("state_off", e.get("command_off", 0)) != 0:
                    fail(f"{where}: a coil that reads 0 must mean off")
    if not all(counts.values()):
        fail(f"empty platform: {counts}")
    # Every register of both units is there once.
    with open(registers_json, encoding="utf-8") as f:
        regs = json.load(f)
    expected = sum(len(u["registers"]) for u in regs["units"]) if "units" in regs else None
    if expected is not None and expected != sum(counts.values()):
        fail(f"{sum(counts.values())} entities for {expected} registers")


KEPWARE_COLUMNS = ["Tag Name", "Address", "Data Type", "Respect Data Type", "Client Access", "Scan Rate",
                   "Scaling", "Raw Low", "Raw High", "Scaled Low", "Scaled High", "Scaled Data Type",
                   "Clamp Low", "Clamp High", "Eng Units", "Description", "Negate Value"]
KEPWARE_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]*(\.[A-Za-z][A-Za-z0-9_]*)*$")


def check_kepware(path):
    raw = open(path, "rb").read()
    for line_no, line in enumerate(raw.split(b"\n"), 1):
        if any(b > 0x7E or (b < 0x20 and b not in (0x09, 0x0D)) for b in line):
            fail(f"line {line_no}: not plain ASCII (imports as mojibake): {line[:80]!r}")
    rows = list(csv.reader(raw.decode("ascii", "replace").splitlines()))
    if rows[0] != KEPWARE_COLUMNS:
        fail(f"header {rows[0]}")
    groups = set()
    for row in rows[1:]:
        if len(row) != len(KEPWARE_COLUMNS):
            fail(f"{row[0]}: {len(row)} fields")
            continue
        name = row[0]
        if not KEPWARE_NAME.match(name):
            fail(f"{name}: not a Kepware tag name (letters, digits, _; dots separate groups)")
        if "." in name:
            groups.add(name.rsplit(".", 1)[0])
        if len(row[15]) > 255:
            fail(f"{name}: description of {len(row[15])} characters")
        if not re.fullmatch(r"[0-4]\d{5}", row[1]):
            fail(f"{name}: address {row[1]}")
    if len(groups) < 3:
        fail(f"tags do not import as groups: {sorted(groups)[:5]}")


def main():
    kind = sys.argv[1]
    if kind == "home-assistant":
        check_home_assistant(sys.argv[2], sys.argv[3])
    elif kind == "kepware":
        check_kepware(sys.argv[2])
    else:
        sys.exit(f"unknown check {kind}")
    for f in failures[:40]:
        print(f)
    if failures:
        print(f"{len(failures)} problem(s) in {sys.argv[2]}")
        sys.exit(1)
    print(f"{sys.argv[2]}: ok")


main()
