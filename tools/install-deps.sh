#!/usr/bin/env bash
# Installs the Debian 12 packages the module builds, tests and runs with.
# Idempotent: only what is missing is installed; a machine that has everything
# does not touch apt at all.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config ccache
  libmodbus-dev libgpiod-dev libsqlite3-dev sqlite3 libsystemd-dev
  catch2 libcli11-dev libtomlplusplus-dev libspdlog-dev libfmt-dev
  libssl-dev openssl
  # MQTT / Sparkplug B (sparkplug/): client, broker for the tests, payloads, test subscriber
  libmosquitto-dev mosquitto protobuf-compiler libprotobuf-dev python3-paho-mqtt python3-protobuf
  nlohmann-json3-dev libbenchmark-dev
  mbpoll socat python3-pymodbus python3-serial python3-serial-asyncio python3-yaml
  clang-16 libclang-rt-16-dev
  # the .deb and its tests: dpkg-shlibdeps (cpack), systemd-analyze, file
  dpkg-dev systemd file
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
