#!/usr/bin/env bash
# Runs every benchmark of the homing module (a few minutes) and writes
# BENCHMARKS.md at the repository root: Modbus TCP throughput and latency of
# homingd beside a raw TCP ping-pong, a bare libmodbus server and a pymodbus
# server at 1, 8 and 64 clients with homing cycles running; control-loop
# lateness beside a bare clock_nanosleep loop; the engine's step cost; idle CPU
# and memory; homing repeatability and cycle time; durable settings writes
# beside a bare SQLite commit; RTU turnaround over a socat pty pair; Modbus/TCP
# Security (TLS) beside plain TCP on one homingd, and the cost of a handshake;
# the control loop with and without the MQTT edge node, and its bytes per cycle;
# the same axis homed by LinuxCNC 2.9 and by our engine (error against the true
# edge, cycle time), LinuxCNC installed first by bench/install-linuxcnc.sh.
#
#   bash bench/run_benchmarks.sh [BUILD_DIR] [options]
#
# BUILD_DIR defaults to build/. It is configured (Release) and built if its
# benchmark programs are missing. Options go to bench/run_benchmarks.py:
#   --rounds N (3)  --duration S (2, per load round)  --clients 1,8,64
#   --out FILE (BENCHMARKS.md)  --quick (one short round of everything: a smoke run)
#   --only tls|peer (measure only the TLS or the LinuxCNC section and replace it in --out)
#   --peer-starts N (60: start positions of the LinuxCNC comparison, about 2 s each)
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="build"
if [ $# -gt 0 ] && [ "${1#--}" = "$1" ]; then
  build="$1"
  shift
fi
case "$build" in /*) ;; *) build="$root/$build" ;; esac

for tool in /usr/bin/python3 socat cmake; do
  command -v "$tool" >/dev/null || { echo "run_benchmarks: $tool is missing: bash tools/install-deps.sh" >&2; exit 1; }
done

progs=(homingd modbus_load bare_modbus_server tcp_pingpong loop_floor sqlite_commit engine_step_bench
       homing_repeatability tls_load homing_peer)
targets=()
case " $* " in *" --only peer "*) progs=(homing_peer); targets=(--target homing_peer) ;; esac
need_build=0
for prog in "${progs[@]}"; do
  [ -x "$build/bin/$prog" ] || need_build=1
done
if [ "$need_build" = 1 ]; then
  echo "run_benchmarks: building in $build" >&2
  if [ ! -f "$build/CMakeCache.txt" ]; then
    cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
  fi
  cmake --build "$build" "${targets[@]}" >/dev/null
fi

# The homing peer's LinuxCNC: the benchmark brings it itself (the test suite
# does not need it). Without it the run goes on and its section says why.
if ! bash "$root/bench/install-linuxcnc.sh"; then
  echo "run_benchmarks: LinuxCNC could not be installed: the homing comparison will say so" >&2
fi

cd "$root"
exec /usr/bin/python3 "$root/bench/run_benchmarks.py" --build "$build" "$@"
