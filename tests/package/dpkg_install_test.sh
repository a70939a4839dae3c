#!/usr/bin/env bash
# Opt-in ctest entry (tests/package/CMakeLists.txt): installs the .deb on THIS
# machine with dpkg -i, checks what the package promised, then purges it and
# removes the user and state directory it created. Fails (never skips) when
# not root or when homingd is already installed here.
#   dpkg_install_test.sh DEB_DIR
set -euo pipefail
deb=$(ls "$1"/*.deb)
fail() { echo "FAIL: $*" >&2; exit 1; }

[ "$(id -u)" -eq 0 ] || fail "dpkg -i needs root (this test was opted into with HOMING_TEST_DPKG_INSTALL)"
if dpkg-query -W -f='${Status}' homingd 2>/dev/null | grep -q "install ok installed"; then
  fail "homingd is already installed on this machine; this test will not replace it"
fi
user_existed=no; getent passwd homingd >/dev/null && user_existed=yes
state_existed=no; [ -e /var/lib/homingd ] && state_existed=yes

cleanup() {
  dpkg --purge homingd >/dev/null 2>&1 || true
  if [ "$user_existed" = no ] && getent passwd homingd >/dev/null; then deluser --quiet --system homingd || true; fi
  if [ "$user_existed" = no ] && getent group homingd >/dev/null; then delgroup --quiet --system homingd || true; fi
  if [ "$state_existed" = no ]; then rm -rf /var/lib/homingd; fi
}
trap cleanup EXIT

dpkg -i "$deb" || fail "dpkg -i $deb"
dpkg-query -W -f='${Status}' homingd | grep -q "install ok installed" || fail "homingd not installed"
dpkg-query -W -f='${Conffiles}' homingd | grep -q "/etc/homingd/homingd.toml" || fail "conffile not registered"

entry=$(getent passwd homingd) || fail "no homingd user"
uid=$(echo "$entry" | cut -d: -f3)
[ "$uid" -lt 1000 ] || fail "homingd is not a system user (uid $uid)"
case "$entry" in *nologin|*/bin/false) ;; *) fail "homingd has a login shell: $entry" ;; esac
[ "$(stat -c '%U:%G %a' /var/lib/homingd)" = "homingd:homingd 750" ] || fail "/var/lib/homingd: $(stat -c '%U:%G %a' /var/lib/homingd)"
for f in /usr/bin/homingd /usr/bin/homingctl /usr/lib/systemd/system/homingd.service /etc/homingd/homingd.toml \
         /usr/share/homingd/hmi_maps/registers.csv /usr/share/doc/homingd/copyright; do
  [ -e "$f" ] || fail "$f missing"
done
/usr/bin/homingd --version | grep -q homingd || fail "homingd --version"

# The service user can write its database where the config says (an import
# creates it, an export reads it back).
seed=$(mktemp /tmp/dpkg-test-XXXXXX.toml)
printf 'format = "homing-module-settings"\nformat_version = 2\n[settings]\naxis.x.pull_off = 1.0\n' > "$seed"
chmod 644 "$seed"
setpriv --reuid homingd --regid homingd --init-groups \
  /usr/bin/homingd --config /etc/homingd/homingd.toml --db /var/lib/homingd/dpkg-test.db \
  --import-settings "$seed" >/dev/null || fail "homingd as user homingd cannot create its database in /var/lib/homingd"
setpriv --reuid homingd --regid homingd --init-groups \
  /usr/bin/homingd --config /etc/homingd/homingd.toml --db /var/lib/homingd/dpkg-test.db \
  --export-settings /var/lib/homingd/dpkg-test.toml >/dev/null || fail "homingd as user homingd cannot use /var/lib/homingd"
rm -f /var/lib/homingd/dpkg-test.* "$seed"

dpkg --purge homingd || fail "dpkg --purge"
[ ! -e /usr/bin/homingd ] || fail "/usr/bin/homingd left after purge"
[ ! -e /etc/homingd/homingd.toml ] || fail "conffile left after purge"
echo "dpkg -i, the service user, /var/lib/homingd and purge: ok"
