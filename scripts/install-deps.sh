#!/usr/bin/env bash
# Installs everything leakmon builds, tests and benchmarks with, from Debian 12 packages only.
set -euo pipefail
SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -o DPkg::Lock::Timeout=300
$SUDO apt-get install -y --no-install-recommends -o DPkg::Lock::Timeout=300 \
  build-essential cmake ninja-build pkg-config git clang clang-format libclang-rt-14-dev \
  libspdlog-dev libfmt-dev libeigen3-dev libyaml-cpp-dev libmodbus-dev libsystemd-dev \
  libmicrohttpd-dev \
  libgtest-dev libgmock-dev libbenchmark-dev \
  libmosquitto-dev mosquitto mosquitto-clients prometheus \
  python3 python3-numpy python3-pywt python3-matplotlib python3-pymodbus python3-serial python3-serial-asyncio python3-can \
  socat can-utils rt-tests stress-ng systemd \
  qemu-system-x86 busybox-static xz-utils cpio \
  prometheus python3-yaml \
  chromium chromium-driver python3-selenium
