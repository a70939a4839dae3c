#!/usr/bin/python3
"""End-to-end: homingd --mqtt mqtts:// against Debian's mosquitto with TLS,
client certificates and a password file, on loopback. The certificates come
from the project's recipe (tools/tls/make-certs.sh); the broker's password file
from mosquitto_passwd. An independent subscriber (paho-mqtt with its own client
certificate) sees the birth only from a module that is let in.

usage: sparkplug_tls_e2e.py HOMINGD PYTHON_DIR MAKE_CERTS"""
import os, ssl, subprocess, sys, tempfile, time

from e2e_support import (Broker, check, failures, free_port, import_sparkplug, shut_down, sparkplug_host, start_homingd,
                         wait_until)

homingd, pydir, make_certs = sys.argv[1], sys.argv[2], sys.argv[3]
import_sparkplug(pydir)

work = tempfile.mkdtemp(prefix="mqtt-tls-e2e-")
pki = os.path.join(work, "pki")
subprocess.run(["bash", make_certs, "init", pki], check=True, timeout=120, stdout=subprocess.DEVNULL)
pwfile = os.path.join(work, "broker.passwd")
subprocess.run(["/usr/bin/mosquitto_passwd", "-c", "-b", pwfile, "module", "s3cret-pw"], check=True, timeout=30)
# Started as root, mosquitto drops to its own user before it reads its files:
# let that user reach the broker's key and password file (test files only).
for path in (work, pki):
    os.chmod(path, 0o755)
for path in (pwfile, f"{pki}/server.key"):
    os.chmod(path, 0o644)

broker = Broker(work, f"cafile {pki}/ca.crt\ncertfile {pki}/server.crt\nkeyfile {pki}/server.key\n"
                      "require_certificate true\n"
                      f"password_file {pwfile}\nallow_anonymous false\npersistence false\n")
broker_port = broker.port

messages = []
def with_certificate(client):
    client.tls_set(ca_certs=f"{pki}/ca.crt", certfile=f"{pki}/operator.crt", keyfile=f"{pki}/operator.key",
                   cert_reqs=ssl.CERT_REQUIRED)
    client.username_pw_set("module", "s3cret-pw")
sub = sparkplug_host("tls-e2e-host", broker, lambda kind, node, p, _msg: messages.append((kind, node, p)),
                     setup=with_certificate, started="mosquitto with TLS did not start")

def births(node): return [p for t, n, p in messages if t == "NBIRTH" and n == node]
pw_ok = os.path.join(work, "module.pw"); open(pw_ok, "w").write("s3cret-pw\n"); os.chmod(pw_ok, 0o600)
pw_bad = os.path.join(work, "wrong.pw"); open(pw_bad, "w").write("guessed\n"); os.chmod(pw_bad, 0o600)

def start(node, *extra):
    log = open(os.path.join(work, node + ".log"), "w")
    return start_homingd(homingd, free_port(), os.path.join(work, node + ".db"), broker.url("mqtts"), node,
                         "--mqtt-ca", f"{pki}/ca.crt", *extra, log=log, time_scale=None)

def log_of(node): return open(os.path.join(work, node + ".log")).read()

daemons = []
try:
    good = start("good", "--mqtt-cert", f"{pki}/engineer.crt", "--mqtt-key", f"{pki}/engineer.key",
                 "--mqtt-user", "module", "--mqtt-password-file", pw_ok)
    no_cert = start("nocert", "--mqtt-user", "module", "--mqtt-password-file", pw_ok)
    bad_pw = start("badpw", "--mqtt-cert", f"{pki}/engineer.crt", "--mqtt-key", f"{pki}/engineer.key",
                   "--mqtt-user", "module", "--mqtt-password-file", pw_bad)
    daemons = [good, no_cert, bad_pw]
    check(wait_until(lambda: len(births("good")) >= 1, 20),
          "a module with its client certificate, user and password is born over TLS")
    if births("good"):
        check(any(m.name == "status/state" for m in births("good")[0].metrics), "its birth carries the metrics")
    check(wait_until(lambda: "not authorised" in log_of("badpw").lower() or "not authorized" in log_of("badpw").lower(), 15),
          "a wrong password: the module's log says the broker refused it as not authorised")
    time.sleep(1.0)
    check(not births("nocert"), "a module without a client certificate is not let in (no birth)")
    check("certificate required" in log_of("nocert"),
          "its log says why: the broker requires a client certificate")
    check(not births("badpw"), "a module with a wrong password is not let in (no birth)")
    check("mqtts://127.0.0.1" in log_of("good") and "as user module" in log_of("good"),
          "the module's log names the TLS broker and the user")
    check("s3cret" not in log_of("good") + log_of("badpw"), "the password never appears in the log")

    # Start-up errors name the option.
    def refused(*args):
        r = subprocess.run([homingd, "--tcp", f"127.0.0.1:{free_port()}", "--db", os.path.join(work, "x.db"), *args],
                           capture_output=True, text=True, timeout=20)
        return r.returncode, r.stderr
    rc, err = refused("--mqtt", f"mqtts://127.0.0.1:{broker_port}")
    check(rc != 0 and "--mqtt-ca" in err, f"mqtts:// without --mqtt-ca is refused naming it: {err.strip()[:120]}")
    rc, err = refused("--mqtt", f"mqtt://127.0.0.1:{broker_port}", "--mqtt-ca", f"{pki}/ca.crt")
    check(rc != 0 and "mqtts://" in err, f"a CA with plain mqtt:// is refused: {err.strip()[:120]}")
    empty = os.path.join(work, "empty.pw"); open(empty, "w").close()
    rc, err = refused("--mqtt", f"mqtt://127.0.0.1:{broker_port}", "--mqtt-user", "module", "--mqtt-password-file", empty)
    check(rc != 0 and "empty.pw" in err and "empty" in err, f"an empty password file is refused naming it: {err.strip()[:120]}")
finally:
    shut_down(daemons, sub, broker)
if failures:
    for node in ("good", "nocert", "badpw"):
        print(f"--- {node} log ---\n" + log_of(node)[-2000:])
sys.exit(1 if failures else 0)
