#!/bin/busybox sh
# SPDX-License-Identifier: Apache-2.0
# shellcheck shell=dash
# Stage-1 PID 1 of the systemd guest (run-systemd-vm-test.sh packs it as /init with busybox and
# the modules in /modules.load): loads the virtio disk and ext4 drivers Debian builds as
# modules, mounts the root disk /dev/vda and hands over to its systemd.
# On a line of its own (the firmware leaves one open): the host's proof of a booted kernel
# (tests/vm/vm-kernel.sh, vm_watch_boot).
printf "\nWEEDSPRAY-VM-INIT\n"
/bin/busybox --install -s /bin
export PATH=/bin
fail() {
  echo "WEEDSPRAY-SD-STAGE1 FAIL: $*"
  poweroff -f
}
mount -t proc proc /proc
mount -t sysfs sysfs /sys
mount -t devtmpfs devtmpfs /dev
while read -r module; do
  insmod "$module" || fail "insmod $module"
done </modules.load
for _ in $(seq 50); do [ -b /dev/vda ] && break; sleep 0.1; done
[ -b /dev/vda ] || fail "no /dev/vda"
mount -t ext4 -o rw /dev/vda /newroot || fail "cannot mount /dev/vda"
umount /proc /sys
mount --move /dev /newroot/dev || umount /dev
exec switch_root /newroot /sbin/init
