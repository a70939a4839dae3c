#!/usr/bin/python3
"""Modbus/TCP Security end-to-end with pymodbus 3.0's TLS client (Debian's
python3-pymodbus, run with /usr/bin/python3), an implementation independent of
OpenSSL's C API as homingd uses it and of libmodbus.

Makes certificates with the README's recipe (tools/tls/make-certs.sh init
--test-set) in a temporary directory, starts homingd with --tls on a free
127.0.0.1 port, then: an engineer reads and writes a setting; an operator can
home but a settings write gets exception 01 and changes nothing; a viewer
only reads; no client certificate, a certificate from another CA, an expired
one and a revoked one are refused at the handshake with the TLS alert that
says why (pymodbus gets no answer), plain Modbus TCP on the TLS port is
closed without a reply, and the log says why. Exits non-zero on the first failure. Every wait is bounded.

pymodbus 3.0's TLS clients default to their own "TLS framer", which sends a
bare PDU with no MBAP header; the Modbus/TCP Security protocol keeps the MBAP
header inside TLS, so the client is given the socket framer. The asyncio
client is used: the synchronous one reads a reply in two parts and waits in
select() for the second, which OpenSSL has already taken off the socket.
"""
import argparse
import asyncio
import csv
import os
import socket
import ssl
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from homingd_py import Daemon, check, failures  # noqa: E402  (also stubs serial_asyncio)

try:
    from pymodbus.client import AsyncModbusTlsClient, ModbusTcpClient
    from pymodbus.exceptions import ConnectionException
    from pymodbus.framer.socket_framer import ModbusSocketFramer
    from pymodbus.pdu import ExceptionResponse
except ImportError as e:  # a missing tool fails the test, never skips it
    print(f"FAIL: pymodbus is not importable ({e}); run tools/install-deps.sh", file=sys.stderr)
    sys.exit(1)


class Map:
    def __init__(self, path):
        with open(path, newline="") as f:
            self.rows = {row["name"]: row for row in csv.DictReader(f)}

    def address(self, name):
        return int(self.rows[name]["address"])


class TlsDaemon(Daemon):
    """homingd with plain TCP (for checks outside TLS) and --tls, each on a free port."""

    def __init__(self, exe, pki, db):
        super().__init__(exe, db, ports=2, extra=lambda p: [
            "--tls", f"127.0.0.1:{p[1]}", "--tls-cert", f"{pki}/server.crt", "--tls-key", f"{pki}/server.key",
            "--tls-ca", f"{pki}/ca.crt", "--tls-crl", f"{pki}/crl.pem"])
        self.tls_port = self.ports[1]


def context(pki, name):
    """What a plant's client does: verify the module against the CA, show its own certificate."""
    ctx = ssl.create_default_context(ssl.Purpose.SERVER_AUTH, cafile=f"{pki}/ca.crt")
    ctx.minimum_version = ssl.TLSVersion.TLSv1_2
    if name:
        ctx.load_cert_chain(f"{pki}/{name}.crt", f"{pki}/{name}.key")
    return ctx


def as_client(daemon, pki, name, actions, timeout=20):
    """Runs actions(client) on a new TLS connection with this certificate; None when it did not connect."""
    async def session():
        c = AsyncModbusTlsClient("127.0.0.1", port=daemon.tls_port, framer=ModbusSocketFramer,
                                 sslctx=context(pki, name), timeout=2, retries=0)
        await c.connect()
        try:
            return await actions(c) if c.connected else None
        finally:
            await c.close()
    return asyncio.run(asyncio.wait_for(session(), timeout))


# A read of status.state (input register 1), as a Modbus TCP frame: MBAP + PDU.
READ_STATE = bytes([0, 1, 0, 0, 0, 6, 1, 4, 0, 1, 0, 1])


def pymodbus_outcome(daemon, pki, name):
    """What pymodbus' TLS client gets for a read with this certificate: "answered", "not connected" (the
    handshake failed in connect()) or "connection lost" (TLS 1.3: the client's side of the handshake ends
    before the module has checked its certificate, so the refusal closes the connection under the first
    request). Anything else (a Modbus exception, a timeout, another error) is returned as it is, so that
    it fails the check instead of passing for a refusal."""
    async def read_state(c):
        return await c.read_input_registers(1, 1, slave=1)
    try:
        rsp = as_client(daemon, pki, name, read_state, timeout=10)
    except ConnectionException as e:
        return "connection lost" if "Connection lost" in str(e) else f"ConnectionException: {e}"
    except Exception as e:  # pylint: disable=broad-except
        return f"{type(e).__name__}: {e}"
    if rsp is None:
        return "not connected"
    if not rsp.isError():
        return "answered"
    return f"error response: {rsp}"


def tls_alert(daemon, pki, name):
    """The TLS alert the module sends this certificate, as the client's TLS layer names it (ssl.SSLError's
    reason: TLSV13_ALERT_CERTIFICATE_REQUIRED, TLSV1_ALERT_UNKNOWN_CA, ...), or "answered" when it answers
    a read. pymodbus logs and swallows the alert, so it is read here with the client's own context on a
    plain socket; with TLS 1.3 it comes with the first read."""
    with socket.create_connection(("127.0.0.1", daemon.tls_port), timeout=10) as raw:
        try:
            with context(pki, name).wrap_socket(raw, server_hostname="127.0.0.1") as tls:
                tls.sendall(READ_STATE)
                reply = tls.recv(64)
                return "answered" if reply else "closed without an alert"
        except ssl.SSLError as e:
            return e.reason or str(e)
        except OSError as e:
            return f"{type(e).__name__}: {e}"


def refused_plain(port):
    """Plain Modbus TCP to this port: "closed" when the module closes the connection without a byte of
    reply, else what came back."""
    with socket.create_connection(("127.0.0.1", port), timeout=10) as s:
        s.sendall(READ_STATE)
        try:
            got = s.recv(64)
        except ConnectionResetError:
            return "closed"
        except socket.timeout:
            return "no answer and not closed within 10 s"
        return "closed" if got == b"" else f"reply {got.hex()}"


def is_exception(rsp, code):
    return isinstance(rsp, ExceptionResponse) and rsp.exception_code == code


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--homingd", required=True)
    ap.add_argument("--make-certs", required=True)
    ap.add_argument("--map", required=True)
    args = ap.parse_args()
    regs = Map(args.map)
    feed = regs.address("axis.x.seek_feedrate")

    with tempfile.TemporaryDirectory(prefix="pymodbus-tls-") as tmp:
        pki = os.path.join(tmp, "pki")
        subprocess.run(["bash", args.make_certs, "init", pki, "--test-set"], check=True, timeout=120,
                       stdout=subprocess.DEVNULL)
        d = TlsDaemon(args.homingd, pki, os.path.join(tmp, "settings.db"))
        try:
            async def engineer(c):
                before = await c.read_holding_registers(feed, 1, slave=1)
                written = await c.write_register(feed, 1200, slave=1)
                after = await c.read_holding_registers(feed, 1, slave=1)
                return before, written, after
            got = as_client(d, pki, "engineer", engineer)
            check(got is not None, "engineer: TLS connection")
            if got:
                before, written, after = got
                check(not before.isError() and before.registers == [1000], f"engineer reads axis.x.seek_feedrate: {before}")
                check(not written.isError(), f"engineer writes axis.x.seek_feedrate: {written}")
                check(not after.isError() and after.registers == [1200], f"engineer reads back 1200: {after}")

            async def operator(c):
                refused_write = await c.write_register(feed, 1500, slave=1)
                unchanged = await c.read_holding_registers(feed, 1, slave=1)
                home = await c.write_coil(regs.address("cmd.home_all"), True, slave=1)
                started = False
                deadline = time.monotonic() + 5
                while time.monotonic() < deadline and not started:
                    state = await c.read_input_registers(regs.address("status.state"), 1, slave=1)
                    homing = await c.read_discrete_inputs(regs.address("status.homing"), 1, slave=1)
                    started = (not homing.isError() and homing.bits[0]) or (not state.isError() and state.registers[0] == 2)
                    await asyncio.sleep(0.05)
                return refused_write, unchanged, home, started
            got = as_client(d, pki, "operator", operator)
            check(got is not None, "operator: TLS connection")
            if got:
                refused_write, unchanged, home, started = got
                check(is_exception(refused_write, 1), f"operator settings write: exception 01: {refused_write}")
                check(not unchanged.isError() and unchanged.registers == [1200],
                      f"operator: the setting did not change: {unchanged}")
                check(not home.isError(), f"operator: cmd.home_all accepted: {home}")
                check(started, "operator: the homing cycle started")

            async def viewer(c):
                read = await c.read_holding_registers(feed, 1, slave=1)
                command = await c.write_coil(regs.address("cmd.abort"), True, slave=1)
                heartbeat = await c.write_register(regs.address("host.heartbeat"), 5, slave=1)
                return read, command, heartbeat
            got = as_client(d, pki, "viewer", viewer)
            check(got is not None, "viewer: TLS connection")
            if got:
                read, command, heartbeat = got
                check(not read.isError() and read.registers == [1200], f"viewer reads: {read}")
                check(is_exception(command, 1), f"viewer command: exception 01: {command}")
                check(is_exception(heartbeat, 1), f"viewer heartbeat: exception 01: {heartbeat}")

            # Each refused certificate: the alert the README names, pymodbus gets no answer, the log says why.
            check(tls_alert(d, pki, "engineer") == "answered", "an engineer is answered (the refusal checks' control)")
            check(pymodbus_outcome(d, pki, "engineer") == "answered", "pymodbus: an engineer is answered")
            for name, alert, log in (
                    ("", "TLSV13_ALERT_CERTIFICATE_REQUIRED", ("the client sent no certificate",)),
                    ("other-ca-engineer", "TLSV1_ALERT_UNKNOWN_CA", ("CN=other-ca-engineer", "not signed by the CA of --tls-ca")),
                    ("expired", "SSLV3_ALERT_CERTIFICATE_EXPIRED", ("CN=expired", "certificate has expired")),
                    ("revoked", "SSLV3_ALERT_CERTIFICATE_REVOKED", ("CN=revoked", "certificate revoked"))):
                who = name or "no certificate"
                got = tls_alert(d, pki, name)
                check(got == alert, f"{who}: refused with the alert {alert}: {got}")
                got = pymodbus_outcome(d, pki, name)
                check(got in ("not connected", "connection lost"), f"{who}: pymodbus gets no answer: {got}")
                check(d.log_has("tls: refused 127.0.0.1:", *log), f"log: {who}: {' '.join(log)}")

            control = ModbusTcpClient("127.0.0.1", port=d.port, timeout=1, retries=0)
            rsp = control.read_input_registers(1, 1, slave=1) if control.connect() else None
            control.close()
            check(rsp is not None and not rsp.isError(), f"plain Modbus TCP on the TCP port: answered: {rsp}")
            got = refused_plain(d.tls_port)
            check(got == "closed", f"plain Modbus TCP on the TLS port: closed without a reply: {got}")
            check(d.log_has("tls: refused", "not a TLS handshake"), "log: plain Modbus TCP on the TLS port")
        finally:
            if d.finish() and failures:  # finish() printed the log when the daemon's end was wrong
                with open(d.log_path, errors="replace") as f:
                    print("--- homingd log ---\n" + f.read())
    if failures:
        print(f"{len(failures)} failure(s)")
        sys.exit(1)
    print("all passed")


if __name__ == "__main__":
    main()
