#!/usr/bin/env bash
# Installs LinuxCNC (Debian's linuxcnc-uspace, 2.9) for the benchmarks' homing
# peer (bench/linuxcnc/, BENCHMARKS.md "Homing beside LinuxCNC"), if it is not
# installed yet. Only the benchmarks need it: tools/install-deps.sh, the build
# and the test suite do not. Called by bench/run_benchmarks.sh; safe to run
# again (it does nothing once the package is there).
#
#   bash bench/install-linuxcnc.sh
#
# Exits 0 when LinuxCNC is installed (now or before), non-zero with apt's own
# words when it could not be.
set -euo pipefail

pkg=linuxcnc-uspace
installed() {
  [ "$(dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null)" = "install ok installed" ] && command -v linuxcnc >/dev/null
}
if installed; then
  exit 0
fi

if [ "$(id -u)" = 0 ]; then
  as_root=()
elif command -v sudo >/dev/null; then
  as_root=(sudo)
else
  echo "install-linuxcnc: $pkg is missing and this is not root: run as root: apt-get install --no-install-recommends $pkg" >&2
  exit 1
fi

echo "install-linuxcnc: installing $pkg (LinuxCNC, the benchmarks' homing peer)" >&2
export DEBIAN_FRONTEND=noninteractive
# The package lists may be old or absent on a fresh machine: the install
# names a version the mirror no longer has. Update once, then install.
"${as_root[@]}" apt-get update -qq >&2 || true
"${as_root[@]}" apt-get install -y -qq --no-install-recommends "$pkg" >&2
installed || { echo "install-linuxcnc: $pkg still not installed" >&2; exit 1; }
