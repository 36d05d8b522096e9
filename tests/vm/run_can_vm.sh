#!/usr/bin/env bash
# Boots Debian's own kernel (linux-image-amd64) under qemu with software emulation, loads the
# CAN modules, creates vcan0 and runs the SocketCAN probe there (see
# ../shared/recipes/socketcan-vm.md for why each step is as it is).
#
# usage: run_can_vm.sh PROBE_BINARY CACHE_DIR
# Exit: 0 pass, 1 fail, 77 skipped because a prerequisite cannot be had (the reason is printed).
# The VM's own lines are printed with the prefix "vm| " so they are not taken for ours.
set -euo pipefail
probe=$1
cache=$2
skip() { echo "SKIP: $*"; exit 77; }

command -v qemu-system-x86_64 >/dev/null || skip "qemu-system-x86_64 is not installed (apt-get install qemu-system-x86)"
busybox=/bin/busybox
[ -x "$busybox" ] && ! ldd "$busybox" >/dev/null 2>&1 || skip "a static busybox is not installed (apt-get install busybox-static)"
for tool in cansend cangen; do
  command -v "$tool" >/dev/null || skip "$tool is not installed (apt-get install can-utils)"
done
command -v xz >/dev/null || skip "xz is not installed (apt-get install xz-utils)"
[ -x "$probe" ] || { echo "FAIL: probe binary $probe missing"; exit 1; }

# The kernel: the package linux-image-amd64 currently depends on, downloaded once per build tree.
mkdir -p "$cache"
package=$(apt-cache depends linux-image-amd64 2>/dev/null | awk '/Depends: linux-image-[0-9]/ {print $2; exit}')
[ -n "$package" ] || skip "apt-cache does not know linux-image-amd64 (run apt-get update)"
kernel_dir=$cache/$package
if [ ! -f "$kernel_dir/vmlinux" ]; then
  rm -rf "$kernel_dir" && mkdir -p "$kernel_dir/deb"
  (cd "$kernel_dir/deb" && apt-get download "$package" >/dev/null 2>&1) ||
    skip "cannot download $package with apt-get download"
  dpkg-deb --fsys-tarfile "$kernel_dir"/deb/*.deb | tar -x -C "$kernel_dir" --wildcards \
    './boot/vmlinuz-*' './lib/modules/*/kernel/net/can/*' './lib/modules/*/kernel/drivers/net/can/*'
  # Boot the uncompressed ELF: decompressing a bzImage costs seconds under emulation.
  vmlinuz=$(ls "$kernel_dir"/boot/vmlinuz-*)
  offset=$(LC_ALL=C grep -abo $'\xfd7zXZ' "$vmlinuz" | head -1 | cut -d: -f1)
  [ -n "$offset" ] || { echo "FAIL: no xz payload in $vmlinuz"; exit 1; }
  tail -c +$((offset + 1)) "$vmlinuz" | xz -dc > "$kernel_dir/vmlinux.part" 2>/dev/null || true
  mv "$kernel_dir/vmlinux.part" "$kernel_dir/vmlinux"
  rm -rf "$kernel_dir/deb"
fi

# The initramfs: busybox, the four modules, can-utils with its libraries, /init, the probe.
root=$cache/initramfs
rm -rf "$root" && mkdir -p "$root"/{bin,dev,proc,sys,tmp,lib/modules}
cp "$busybox" "$root/bin/busybox"
for applet in sh mount insmod ip dd sleep poweroff echo printf cat; do ln -s busybox "$root/bin/$applet"; done
for module in can can-raw can-dev vcan; do
  cp "$(find "$kernel_dir/lib/modules" -name "$module.ko" | head -1)" "$root/lib/modules/"
done
for tool in cansend cangen; do
  cp "$(command -v "$tool")" "$root/bin/"
  for lib in $(ldd "$(command -v "$tool")" | grep -o '/[^ ]*'); do
    mkdir -p "$root$(dirname "$lib")" && cp -L "$lib" "$root$lib"
  done
done
cp "$probe" "$root/bin/can_vm_probe"
cat > "$root/init" <<'INIT'
#!/bin/sh
export PATH=/bin
mount -t proc proc /proc
mount -t sysfs sys /sys
mount -t devtmpfs dev /dev
mount -t tmpfs tmp /tmp
verdict() {  # isa-debug-exit: qemu exits with (v << 1) | 1, so 1 = pass, 3 = fail
  printf "\\$1" | dd of=/dev/port bs=1 seek=244 count=1 2>/dev/null
  poweroff -f
}
for m in can can-raw can-dev vcan; do
  insmod /lib/modules/$m.ko || { echo "INIT-ERROR insmod $m"; verdict 001; }
done
ip link add dev vcan0 type vcan && ip link set vcan0 mtu 72 && ip link set up vcan0 ||
  { echo "INIT-ERROR vcan0"; verdict 001; }
if /bin/can_vm_probe; then verdict 000; else verdict 001; fi
INIT
chmod +x "$root/init"
(cd "$root" && find . | "$busybox" cpio -o -H newc 2>/dev/null | gzip -1) > "$cache/initramfs.gz"

# -accel tcg: the /dev/kvm here is nested and a stock kernel crashes on it.
log=$cache/console.log
set +e
timeout 120 qemu-system-x86_64 -accel tcg -m 256 -nodefaults -display none -serial stdio \
  -device isa-debug-exit,iobase=0xf4,iosize=4 -no-reboot -kernel "$kernel_dir/vmlinux" \
  -initrd "$cache/initramfs.gz" -append 'console=ttyS0 quiet panic=-1' </dev/null |
  tr -d '\r' > "$log"
status=${PIPESTATUS[0]}
set -e
sed 's/^/vm| /' "$log"
if [ "$status" = 1 ] && grep -q '^VM-VERDICT pass' "$log"; then
  echo "SocketCAN VM test passed ($package)"
  exit 0
fi
echo "FAIL: SocketCAN VM test (qemu exit $status; 1 = pass, 3 = probe failed, 124 = timeout)"
exit 1
