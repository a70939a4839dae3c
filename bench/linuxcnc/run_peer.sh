#!/usr/bin/env bash
# Runs LinuxCNC headless on peer.ini: homes its four simulated joints from
# every start position in STARTS and prints peer_display.py's "PEER ..." lines
# (among LinuxCNC's own output) on stdout. Used by bench/run_benchmarks.py.
#
#   bash bench/linuxcnc/run_peer.sh WORKDIR STARTS [TIMEOUT_S]
#
# WORKDIR receives a copy of this folder (LinuxCNC writes its position and
# parameter files beside the INI) and the real-time FIFO. STARTS: start
# positions in mm, one a line.
#
# Headless: DISPLAY in peer.ini is peer_display.py, a Python program on
# Debian's /usr/bin/python3 (the linuxcnc and hal modules are Debian's), so no
# X server is needed; `linuxcnc -r` keeps stdout and stderr here instead of
# redirecting them to files. The servo thread runs as an ordinary POSIX
# thread ("Note: Using POSIX non-realtime"): this kernel is not PREEMPT_RT, and
# LinuxCNC measures its homing in servo periods, so a late period slows the
# run down but does not change a homing's figures.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
work="${1:?usage: run_peer.sh WORKDIR STARTS [TIMEOUT_S]}"
starts="${2:?usage: run_peer.sh WORKDIR STARTS [TIMEOUT_S]}"
limit="${3:-600}"

command -v linuxcnc >/dev/null || { echo "run_peer: linuxcnc is not installed (bash bench/install-linuxcnc.sh)" >&2; exit 3; }

# One LinuxCNC per machine (its lock file is /tmp/linuxcnc.lock): the linuxcnc
# script, finding the lock without a terminal, kills the running instance's
# processes to start anew. Never do that to someone else's LinuxCNC.
# (One pgrep per name: pgrep matches nothing for a pattern over 15 characters.)
if [ -e /tmp/linuxcnc.lock ]; then
  for name in milltask rtapi_app linuxcncsvr; do
    if pgrep -x "$name" >/dev/null; then
      echo "run_peer: another LinuxCNC is running (/tmp/linuxcnc.lock, process $name)" >&2
      exit 4
    fi
  done
fi

cfg="$work/linuxcnc"
rm -rf "$cfg"
mkdir -p "$cfg"
cp "$here/peer.ini" "$here/peer.hal" "$here/peer_display.py" "$cfg/"
chmod +x "$cfg/peer_display.py"
starts="$(cd "$(dirname "$starts")" && pwd)/$(basename "$starts")"

# rtapi_app is setuid root; started by root it refuses to run unless told
# which unprivileged user to fall back to (RTAPI_UID), and that user must be
# able to create the FIFO it listens on: a directory of its own under /tmp
# (WORKDIR may be private to root), removed at the end.
fifo="$(mktemp -d /tmp/linuxcnc-peer.XXXXXX)"
trap 'rm -rf "$fifo"' EXIT
if [ "$(id -u)" = 0 ]; then
  RTAPI_UID="$(id -u nobody)"
  export RTAPI_UID
  chown "$RTAPI_UID" "$fifo"
fi
export RTAPI_FIFO_PATH="$fifo/rtapi_fifo"

export PEER_STARTS="$starts"
unset DISPLAY  # nothing of LinuxCNC's may reach for an X server
cd "$cfg"
# timeout's TERM reaches the linuxcnc script, whose trap shuts LinuxCNC down.
rc=0
timeout --kill-after=10 "$limit" linuxcnc -r "$cfg/peer.ini" </dev/null || rc=$?
# The script returns while rtapi_app and milltask may still be exiting; the
# benchmark that follows must not share the cores with them. Wait (at most
# 10 s) until they are gone: LinuxCNC runs one instance per machine, checked
# above, so these are this run's.
for _ in $(seq 100); do
  pgrep -x rtapi_app >/dev/null || pgrep -x milltask >/dev/null || pgrep -x linuxcncsvr >/dev/null || break
  sleep 0.1
done
exit "$rc"
