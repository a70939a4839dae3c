#!/usr/bin/env python3
"""Writes the seed corpus of the fuzz targets into fuzz/corpus/<target>/.

Run from the repository root: python3 fuzz/make_corpus.py. The files are
committed; rerunning rewrites the same files. Kept as they are, not written
here: fuzz_settings_import/exported.toml (`homingd --export-settings` of a
fresh database), fuzz_config/gpiod (the example of homing/gpiod/README.md) and
inputs that once found a bug (fuzz_config/no_tcp_bad_value,
fuzz_settings_import/format_version_huge_float)."""
import os
import struct

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "corpus")


def write(target, name, data):
    d = os.path.join(ROOT, target)
    os.makedirs(d, exist_ok=True)
    if isinstance(data, str):
        data = data.encode()
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


def be16(*v):
    return b"".join(struct.pack(">H", x) for x in v)


# ---------------------------------------------------------------- PDUs
READS = {
    "fc01_coils": b"\x01" + be16(0, 8),
    "fc02_discrete": b"\x02" + be16(0, 16),
    "fc03_holding": b"\x03" + be16(100, 40),
    "fc04_input": b"\x04" + be16(0, 40),
    "fc04_positions": b"\x04" + be16(104, 12),
    "fc03_sim": b"\x03" + be16(100, 20),
}
WRITES = {
    "fc05_home_all": b"\x05" + be16(0, 0xFF00),
    "fc05_abort": b"\x05" + be16(1, 0xFF00),
    "fc05_jog_plus_x": b"\x05" + be16(101, 0xFF00),
    "fc05_move_x": b"\x05" + be16(103, 0xFF00),
    "fc05_lock": b"\x05" + be16(4, 0xFF00),
    "fc06_seek_feedrate": b"\x06" + be16(102, 1500),
    "fc06_heartbeat": b"\x06" + be16(20, 7),
    "fc06_unlock": b"\x06" + be16(30, 0xBEEF),
    "fc06_watchdog": b"\x06" + be16(12, 500),
    "fc06_home_axes_xyz": b"\x06" + be16(40, 7),
    "fc16_home_axes_x": b"\x10" + be16(40, 1) + b"\x02" + be16(1),
    "fc15_coils": b"\x0f" + be16(0, 2) + b"\x01\x00",
    "fc16_pull_off": b"\x10" + be16(126, 2) + b"\x04" + be16(0, 2500),
    "fc16_target_x": b"\x10" + be16(160, 2) + b"\x04" + be16(0, 5000),
    "fc16_half_of_32bit": b"\x10" + be16(127, 1) + b"\x02" + be16(1),
    "fc23_read_write": b"\x17" + be16(100, 4, 102, 1) + b"\x02" + be16(1200),
}
OTHER = {
    "fc43_14_basic": b"\x2b\x0e\x01\x00",
    "fc43_14_object": b"\x2b\x0e\x04\x02",
    "fc20_trace": b"\x14\x07\x06" + be16(1, 0, 4),
    "fc20_two_files": b"\x14\x0e\x06" + be16(1, 0, 2) + b"\x06" + be16(2, 0, 2),
    "fc08_unsupported": b"\x08" + be16(0, 0x1234),
    "fc03_bad_count": b"\x03" + be16(0, 0),
    "fc03_short": b"\x03\x00",
    "fc16_bad_bytes": b"\x10" + be16(100, 2) + b"\x03" + be16(1, 2),
}
SIM_WRITES = {
    "sim_start_button": b"\x05" + be16(1, 0xFF00),
    "sim_estop": b"\x05" + be16(0, 0xFF00),
    "sim_place_x": b"\x10" + be16(100, 2) + b"\x04" + be16(0, 50000),
}


def mbap(tid, unit, pdu, length=None, protocol=0):
    if length is None:
        length = len(pdu) + 1
    return be16(tid, protocol, length) + bytes([unit]) + pdu


def crc16(data):
    crc = 0xFFFF
    for b in data:
        crc ^= b
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
    return crc


def rtu_chunk(unit, pdu, good_crc=True, fix_flag=0):
    body = bytes([unit]) + pdu
    crc = crc16(body) if good_crc else crc16(body) ^ 0x5A5A
    frame = body + struct.pack("<H", crc)
    return bytes([len(frame), fix_flag]) + frame


# ---------------------------------------------------------------- TCP
t = "fuzz_tcp_request"
for name, pdu in {**READS, **WRITES, **OTHER}.items():
    write(t, name, mbap(1, 1, pdu))
for name, pdu in SIM_WRITES.items():
    write(t, name, mbap(2, 247, pdu))
write(t, "unknown_unit", mbap(3, 9, READS["fc03_holding"]))
write(t, "session_unlock_then_write",
      mbap(1, 1, WRITES["fc06_unlock"]) + mbap(2, 1, WRITES["fc06_seek_feedrate"]) + mbap(3, 1, WRITES["fc05_lock"]))
write(t, "session_jog_then_release",
      mbap(1, 1, WRITES["fc05_jog_plus_x"]) + mbap(2, 1, READS["fc04_positions"]) +
      mbap(3, 1, b"\x05" + be16(101, 0)))
write(t, "session_home_read", mbap(1, 1, WRITES["fc05_home_all"]) + mbap(2, 1, READS["fc04_input"]) * 3)
write(t, "mbap_length_0", mbap(1, 1, READS["fc03_holding"], length=0))
write(t, "mbap_length_1", mbap(1, 1, b"", length=1))
write(t, "mbap_length_300", mbap(1, 1, READS["fc03_holding"], length=300))
write(t, "mbap_protocol_1", mbap(1, 1, READS["fc03_holding"], protocol=1))
write(t, "incomplete_frame", mbap(1, 1, READS["fc03_holding"], length=20))
write(t, "two_frames_one_short", mbap(1, 1, READS["fc03_holding"]) + mbap(2, 1, READS["fc03_holding"])[:9])

# ---------------------------------------------------------------- TLS roles
# The same connection streams, played as a viewer and as an operator.
t = "fuzz_tls_roles"
for name, pdu in {**READS, **WRITES, **OTHER}.items():
    write(t, name, mbap(1, 1, pdu))
for name, pdu in SIM_WRITES.items():
    write(t, name, mbap(2, 247, pdu))
write(t, "session_unlock_then_write",
      mbap(1, 1, WRITES["fc06_unlock"]) + mbap(2, 1, WRITES["fc06_seek_feedrate"]) + mbap(3, 1, WRITES["fc05_lock"]))
write(t, "session_home_read", mbap(1, 1, WRITES["fc05_home_all"]) + mbap(2, 1, READS["fc04_input"]) * 3)

# ---------------------------------------------------------------- RTU
t = "fuzz_rtu_frame"
for name, pdu in {**READS, **WRITES, **OTHER}.items():
    write(t, name, rtu_chunk(1, pdu))
write(t, "broadcast_write", rtu_chunk(0, WRITES["fc06_seek_feedrate"]))
write(t, "broadcast_home_all", rtu_chunk(0, WRITES["fc05_home_all"]))
write(t, "broadcast_fc16", rtu_chunk(0, WRITES["fc16_pull_off"]))
write(t, "broadcast_read", rtu_chunk(0, READS["fc03_holding"]))
write(t, "bad_crc", rtu_chunk(1, READS["fc03_holding"], good_crc=False))
write(t, "crc_fixed_by_flag", rtu_chunk(1, WRITES["fc06_heartbeat"], good_crc=False, fix_flag=1))
write(t, "other_unit", rtu_chunk(5, READS["fc03_holding"]))
write(t, "session_unlock_then_write",
      rtu_chunk(1, WRITES["fc06_unlock"]) + rtu_chunk(1, WRITES["fc06_seek_feedrate"]))
write(t, "too_short", bytes([3, 0, 1, 3, 0]))

# ---------------------------------------------------------------- config
t = "fuzz_config"
write(t, "minimal", 'tcp = "127.0.0.1:1502"\n')
write(t, "full", '''tcp = "0.0.0.0:502"
rtu = "/dev/ttyUSB0"
baud = 19200
parity = "E"
stop-bits = 1
unit = 1
sim-unit = 247
db = "homingd.db"
backend = "sim"
period-us = 1000
word-order = "low-first"
max-clients = 8
idle-timeout-s = 30
time-scale = 2.5
log-level = "warn"
write-allow = ["10.0.0.0/24", "192.168.1.10"]
unlock-code = 4321
''')
write(t, "unknown_key", 'tcp = "127.0.0.1:1502"\nbaudrate = 9600\n')
write(t, "unknown_section", '[modbus]\nunit = 3\n')
write(t, "bad_value", 'baud = 12345\n')
write(t, "bad_port", 'tcp = "127.0.0.1:70000"\n')
write(t, "bad_cidr", 'write-allow = "10.0.0.0/33"\n')
write(t, "same_units", 'unit = 5\nsim-unit = 5\n')
write(t, "no_tcp_no_rtu", 'no-tcp = true\n')
write(t, "tls_only", '''no-tcp = true
tls = "0.0.0.0"
tls-cert = "/etc/homingd/tls/server.crt"
tls-key = "/etc/homingd/tls/server.key"
tls-ca = "/etc/homingd/tls/ca.crt"
tls-crl = "/etc/homingd/tls/crl.pem"
tls-default-role = "operator"
''')
write(t, "tls_without_files", 'tls = "0.0.0.0:802"\n')
write(t, "tls_files_without_tls", 'tls_ca = "ca.crt"\n')
write(t, "broken_toml", 'tcp = "127.0.0.1\n[unterminated\n')
write(t, "wrong_type", 'max-clients = "many"\n')
write(t, "help_key", 'help = true\n')
write(t, "empty", '')
# `gpiod` (the [gpiod] example of homing/gpiod/README.md) is kept as is.

# ---------------------------------------------------------------- settings import
t = "fuzz_settings_import"
write(t, "one_value", '''format = "homing-module-settings"
format_version = 1

[settings]
"axis.x.pull_off" = 2500
''')
write(t, "refused_value", '''format = "homing-module-settings"
format_version = 1

[settings]
"axis.x.pull_off" = 3000
"axis.x.seek_feedrate" = 60000
''')
write(t, "out_of_range", '[settings]\n"axis.x.seek_feedrate" = 90000\n')
write(t, "unknown_register", '[settings]\n"axis.q.pull_off" = 1\n')
write(t, "nested_tables", '[settings.axis.x]\npull_off = 1500\nseek_feedrate = 1200\n')
write(t, "wrong_format", 'format = "something-else"\n[settings]\n')
write(t, "future_version", 'format_version = 99\n[settings]\n')
write(t, "no_settings", 'format = "homing-module-settings"\n')
write(t, "string_value", '[settings]\n"axis.x.pull_off" = "2.5 mm"\n')
write(t, "float_value", '[settings]\n"axis.x.pull_off" = 2.5\n')
write(t, "huge_value", '[settings]\n"axis.x.pull_off" = 9223372036854775807\n')
write(t, "engineering_values", '''format = "homing-module-settings"
format_version = 2

[settings]
axis.x.direction = "negative"
axis.x.mode = "switch_reapproach"
axis.x.pull_off = 2.25  # mm
axis.x.seek_feedrate = 1500.0  # mm/min
axis.x.sensor_nc = true
global.allowed_without_homing = "jog_reduced"
sequence.step1 = "x+y"
''')
write(t, "engineering_bad_values", '''format = "homing-module-settings"
format_version = 2

[settings]
axis.x.direction = "sideways"
axis.x.pull_off = 2.0005
axis.x.mode = true
sequence.step1 = "x+q"
''')
write(t, "broken_toml", '[settings\n"axis.x.pull_off" = \n')
