#!/usr/bin/env bash
# Installs what leakmon needs from Debian 12 packages only.
#   install-deps.sh          what building, packaging and running need (README's first command)
#   install-deps.sh --test   that and what the tests and benchmarks need
#   install-deps.sh --check  exit status 1 when a package of --test is not installed
#                            (scripts/test.sh asks, and installs them only then)
set -euo pipefail
SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive

build=(
  build-essential cmake ninja-build pkg-config git
  libspdlog-dev libfmt-dev libeigen3-dev libyaml-cpp-dev libmodbus-dev libsystemd-dev
  libmicrohttpd-dev libmosquitto-dev
  # the Debian package (cpack -G DEB): shared-library dependencies, the man page
  dpkg-dev file help2man
)
test=(
  clang clang-format libclang-rt-14-dev lld
  libgtest-dev libgmock-dev libbenchmark-dev
  mosquitto mosquitto-clients prometheus
  python3 python3-numpy python3-pywt python3-matplotlib python3-pymodbus python3-serial
  python3-serial-asyncio python3-can python3-yaml
  socat can-utils rt-tests stress-ng systemd logrotate bash-completion
  qemu-system-x86 busybox-static xz-utils cpio
  chromium chromium-driver python3-selenium
)
packages=("${build[@]}")
case "${1:-}" in
  "") ;;
  --test) packages+=("${test[@]}") ;;
  --check)
    for p in "${build[@]}" "${test[@]}"; do
      dpkg-query -W -f='${Status}\n' "$p" 2>/dev/null | grep -q "install ok installed" || {
        echo "install-deps: $p is not installed" >&2
        exit 1
      }
    done
    exit 0
    ;;
  *) echo "usage: install-deps.sh [--test | --check]" >&2; exit 2 ;;
esac

$SUDO apt-get update -o DPkg::Lock::Timeout=300
$SUDO apt-get install -y --no-install-recommends -o DPkg::Lock::Timeout=300 "${packages[@]}"
