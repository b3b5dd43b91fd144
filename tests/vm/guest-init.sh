#!/bin/busybox sh
# SPDX-License-Identifier: Apache-2.0
# shellcheck shell=dash
# PID 1 of the test guest (run-vm-tests.sh packs it as /init with busybox, the kernel modules
# listed in /modules.load and the programs under test in /tests).
#
# It sets up what the programs expect, then runs each one and reports on the serial console:
#   WEEDSPRAY-VM-INIT                           the kernel has started /init (first line)
#   WEEDSPRAY-VM-SETUP OK                       simulated GPIO chips and camera are ready
#   WEEDSPRAY-VM-RESULT <program> PASS|FAIL rc=N  one line per program
#   WEEDSPRAY-VM-DONE                           every program has run
# and leaves through QEMU's isa-debug-exit port (x86; on arm64 virt, which has no such port,
# through a PSCI power-off: the host judges by the markers either way).
#
# Guest fixtures (the tests find them through configfs, never by assuming gpiochip numbers):
#   gpio-sim chip labelled "weedspray-out", 8 lines: valve0 valve1 valve2 valve3 pump buzzer lamp aux
#   gpio-sim chip labelled "weedspray-in",  3 lines: flow wheel key
#   gpio-sim chip labelled "weedspray-count", 2 lines: flow_fast flow_fast_gpiod; the kernel's
#     interrupt-cnt counts rising edges of flow_fast (counter named "interrupt-cnt", bound by
#     the test-only interrupt_counter_fixture.ko; count0/enable left 0 for the tests to set)
#   vivid with one video capture node (/dev/video*), timestamps at the start of exposure
# On a line of its own (the firmware leaves one open): the host's proof of a booted kernel
# (vm-kernel.sh, vm_watch_boot).
printf "\nWEEDSPRAY-VM-INIT\n"
/bin/busybox --install -s /bin
export PATH=/bin:/usr/bin
export HOME=/tmp
export GTEST_COLOR=no # the console log is read as text

# QEMU exits with status (code << 1) | 1 when a byte is written to port 0xf4.
leave() {
  if [ -e /dev/port ]; then
    # shellcheck disable=SC2059 # the format is the octal escape of the byte to send
    printf "\\$(printf '%03o' "$1")" | dd of=/dev/port bs=1 seek=244 count=1 2>/dev/null
  fi
  poweroff -f
}
setup_failed() {
  echo "WEEDSPRAY-VM-SETUP FAIL: $*"
  leave 2
}

mount -t proc proc /proc
mount -t sysfs sysfs /sys
mount -t devtmpfs devtmpfs /dev
mount -t tmpfs tmpfs /tmp
mount -t tmpfs tmpfs /run

while read -r module; do
  parameters=""
  # One video capture node only; webcam input first (vivid's default input list).
  case "$module" in
    */vivid.ko) parameters="n_devs=1 node_types=0x1" ;;
    # A fixed node far from vivid's; capture caps only once a writer has set the format.
    */v4l2loopback.ko) parameters="video_nr=20 card_label=weedspray-loopback exclusive_caps=1" ;;
  esac
  # shellcheck disable=SC2086 # parameters are words
  insmod "$module" $parameters || setup_failed "insmod $module failed"
done </modules.load

mount -t configfs configfs /sys/kernel/config || setup_failed "cannot mount configfs"

. /gpio-sim-chip.sh # make_gpio_sim_chip
make_gpio_sim_chip weedspray-out valve0 valve1 valve2 valve3 pump buzzer lamp aux
make_gpio_sim_chip weedspray-in flow wheel key
make_gpio_sim_chip weedspray-count flow_fast flow_fast_gpiod

# interrupt-cnt was loaded above; the fixture gives it flow_fast (x86 has no device tree).
insmod "/lib/modules/$(uname -r)/extra/interrupt_counter_fixture.ko" \
  chip_label=weedspray-count line=0 || setup_failed "insmod interrupt_counter_fixture.ko failed"
counter_dir=""
for dir in /sys/bus/counter/devices/counter*; do
  [ "$(cat "$dir/name" 2>/dev/null)" = interrupt-cnt ] && counter_dir="$dir" && break
done
[ -n "$counter_dir" ] || setup_failed "interrupt-cnt registered no counter named interrupt-cnt"
echo "interrupt-cnt: $counter_dir ($(cat "$counter_dir/signal0/name")), count0 enable=$(cat "$counter_dir/count0/enable")"

video_node=""
for _ in 1 2 3 4 5 6 7 8 9 10; do
  for node in /dev/video*; do
    [ "$node" = /dev/video20 ] && continue # v4l2loopback's
    [ -c "$node" ] && video_node="$node" && break 2
  done
  sleep 0.2
done
[ -n "$video_node" ] || setup_failed "vivid created no /dev/video* node"
echo "vivid: $video_node ($(cat /sys/class/video4linux/"$(basename "$video_node")"/name))"
# vivid stamps "End of Frame" by default: 0.9 frame periods AFTER it hands the buffer over, i.e.
# in the future. Real cameras (UVC) stamp the start of the frame; so does vivid with this.
v4l2-ctl -d "$video_node" -c timestamp_source=1 || setup_failed "cannot set vivid's timestamp_source"
echo "WEEDSPRAY-VM-SETUP OK"

cd /tmp || setup_failed "no /tmp"
# Each program's limit: weedspray.program_timeout_s= on the kernel command line (run-vm-tests.sh
# gives the arm64 guest more: TCG runs aarch64 code more slowly), else 180 s.
program_timeout_s=180
# shellcheck disable=SC2013 # the command line is words
for word in $(cat /proc/cmdline); do
  case "$word" in weedspray.program_timeout_s=*) program_timeout_s="${word#*=}" ;; esac
done
echo "each program may take ${program_timeout_s} s"
failed=0
for program in /tests/*; do
  name="$(basename "$program")"
  echo "WEEDSPRAY-VM-BEGIN $name"
  # A hung program must not eat the whole boot timeout.
  timeout "$program_timeout_s" "$program"
  status=$?
  if [ "$status" -eq 0 ]; then
    echo "WEEDSPRAY-VM-RESULT $name PASS"
  else
    echo "WEEDSPRAY-VM-RESULT $name FAIL rc=$status"
    failed=1
  fi
done
echo "WEEDSPRAY-VM-DONE"
leave "$failed"
