"""Runs every runnable shell block of the given documents, as a reader would,
against a homingd on the simulator that this script starts (run with Debian's
/usr/bin/python3).

A runnable block is a fenced block whose info string is `sh runnable`. Each
document gets its own daemon (a fresh database, 127.0.0.1, a free port, time
10x faster) and its own scratch directory, in which `build/bin` leads to the
programs under test, and its blocks run in order, each with `bash -e -o
pipefail`: one failing command fails the test, naming the document, the line
and the command's output. The blocks are written for a reader's daemon on
127.0.0.1:1502: that address (and mbpoll's `-p 1502`) is replaced by the
test's, and homingctl finds the daemon through the config file it reads
(HOMINGD_CONFIG), as it finds an installed one. A line `! command` must exit
with 1 (refused). A line `command   # shows: PATTERN` must succeed and print a
line showing PATTERN: literal text, a figure `N±T` standing for any number
within T of N (shows.py), so that a figure the text promises is checked, not
only the exit code. A document
without a runnable
block fails too, so a misspelt marker cannot pass unnoticed. The daemon is
ended by its PID with SIGTERM and must exit 0.

usage: run_doc_blocks.py HOMINGD BIN_DIR DOC [DOC...]
"""
import os
import re
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
import homingd_py  # noqa: E402
from homingd_py import check  # noqa: E402

FENCE = re.compile(r"^```(.*)$")


def runnable_blocks(path):
    """(line number of the opening fence, text) of every `sh runnable` block."""
    blocks, inside, info, start, lines = [], False, "", 0, []
    with open(path, encoding="utf-8") as f:
        for number, line in enumerate(f, 1):
            m = FENCE.match(line.rstrip("\n"))
            if m and not inside:
                inside, info, start, lines = True, m.group(1).strip(), number, []
            elif m and inside and m.group(1).strip() == "":
                if info.split() == ["sh", "runnable"]:
                    blocks.append((start, "".join(lines)))
                inside = False
            elif inside:
                lines.append(line)
    return blocks


# A line `! command` in a block is a command that must be refused: the reader
# types it without the `!`, the test requires homingctl's exit code 1 (the
# operation failed: a refusal or an alarm), so that a usage error (2) or no
# answer (3) after a rename does not pass as the refusal the text promises.
MUST_FAIL = """must_be_refused() {
  local code=0
  "$@" || code=$?
  if [ "$code" -eq 0 ]; then echo "expected to be refused, but it succeeded: $*" >&2; return 1; fi
  if [ "$code" -ne 1 ]; then echo "expected exit code 1 (refused), got $code: $*" >&2; return 1; fi
}
"""


# A line `command   # shows: PATTERN`: the command's output (printed as the
# reader sees it) must hold a line showing PATTERN (shows.py). Simple commands only (no
# pipes): the line becomes `must_show 'PATTERN' command...`.
MUST_SHOW = """must_show() {
  local want="$1" out
  shift
  out=$("$@")
  printf '%s\\n' "$out"
  if ! /usr/bin/python3 "$DOC_SHOWS" "$want" <<<"$out"; then echo "expected a line showing '$want' from: $*" >&2; return 1; fi
}
"""
SHOWS = re.compile(r"^(?P<cmd>[^#\n]*?)\s+# shows: (?P<want>.+?)\s*$", re.M)


def shell_quote(text):
    return "'" + text.replace("'", "'\\''") + "'"


def for_port(text, port):
    text = text.replace("127.0.0.1:1502", f"127.0.0.1:{port}")
    text = re.sub(r"-p 1502\b", f"-p {port}", text)
    text = SHOWS.sub(lambda m: f"must_show {shell_quote(m.group('want'))} {m.group('cmd')}", text)
    return MUST_FAIL + MUST_SHOW + re.sub(r"(?m)^! ", "must_be_refused ", text)


def run_document(homingd, bin_dir, doc):
    blocks = runnable_blocks(doc)
    name = os.path.relpath(doc)
    if not check(blocks, f"{name} has runnable blocks"):
        return
    with tempfile.TemporaryDirectory(prefix="docblocks-") as scratch:
        os.makedirs(os.path.join(scratch, "build"))
        os.symlink(os.path.abspath(bin_dir), os.path.join(scratch, "build", "bin"))
        db = os.path.join(scratch, "daemon.db")
        daemon = homingd_py.Daemon(homingd, db)
        config = os.path.join(scratch, "homingd.toml")
        with open(config, "w") as f:
            f.write(f'tcp = "127.0.0.1:{daemon.port}"\ndb = "{db}"\n')
        env = dict(os.environ, HOMINGD_CONFIG=config,
                   DOC_SHOWS=os.path.join(os.path.dirname(os.path.abspath(__file__)), "shows.py"))
        try:
            for line, text in blocks:
                script = for_port(text, daemon.port)
                try:
                    done = subprocess.run(["bash", "-e", "-o", "pipefail", "-c", script], cwd=scratch, env=env,
                                          stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=180)
                    code, out, err = done.returncode, done.stdout, done.stderr
                except subprocess.TimeoutExpired as e:
                    code, out, err = "timeout (180 s)", e.stdout or "", e.stderr or ""
                if not check(code == 0, f"{name}:{line}: the block runs without an error (exit {code})"):
                    print("--- block ---\n" + script + "--- stdout ---\n" + str(out) + "--- stderr ---\n" + str(err))
                    break
                print(out, end="")
        finally:
            daemon.finish()


def main():
    if len(sys.argv) < 4:
        print(__doc__)
        return 2
    homingd, bin_dir = sys.argv[1], sys.argv[2]
    for doc in sys.argv[3:]:
        run_document(homingd, bin_dir, doc)
    if homingd_py.failures:
        print(f"{len(homingd_py.failures)} failure(s):\n  " + "\n  ".join(homingd_py.failures))
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
