#!/usr/bin/env bash
# Installs a leakmon .deb as a user would (apt-get install ./leakmon_*.deb), checks the
# installed service, and purges it again: scripts/test.sh runs it on the Release build's package.
#   check-package.sh PATH/leakmon_VERSION_ARCH.deb
set -euo pipefail
deb=$(realpath "$1")
SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
if dpkg-query -W -f='${Status}' leakmon 2>/dev/null | grep -q "install ok installed"; then
  echo "check-package: leakmon is installed on this machine already; not touching it" >&2
  exit 1
fi
# The purge runs however the checks end.
trap '$SUDO apt-get purge -y -o DPkg::Lock::Timeout=300 leakmon >/dev/null' EXIT

$SUDO apt-get install -y --no-install-recommends -o DPkg::Lock::Timeout=300 "$deb"
set -x
test "$(command -v leakmon)" = /usr/bin/leakmon
leakmon --version
dpkg-query -W -f='${Depends}\n' leakmon
test "$(dpkg-query -W -f='${Conffiles}' leakmon | awk 'NF {print $1}' | sort | tr '\n' ' ')" \
  = "/etc/leakmon/leakmon.yaml /etc/logrotate.d/leakmon "
# The installed configuration is a template for another machine's devices: the file and its
# paths pass, the devices and peers are not probed (there are none in CI).
leakmon check-config --no-probe /etc/leakmon/leakmon.yaml
unit=$(systemctl show -P FragmentPath leakmon.service 2>/dev/null || true)
test -n "$unit" || unit=/lib/systemd/system/leakmon.service
systemd-analyze verify "$unit"
man -w leakmon 2>/dev/null || test -f /usr/share/man/man1/leakmon.1.gz
test -f /usr/share/bash-completion/completions/leakmon
test -f /usr/share/leakmon/prometheus/leakmon-alert-rules.yml
logrotate --debug /etc/logrotate.d/leakmon
set +x

trap - EXIT
$SUDO apt-get purge -y -o DPkg::Lock::Timeout=300 leakmon
test ! -e /usr/bin/leakmon
test ! -e /etc/leakmon/leakmon.yaml
test ! -e "$unit"
echo "check-package: $deb installs, verifies and purges"
