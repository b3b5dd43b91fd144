#!/bin/bash
# SPDX-License-Identifier: Apache-2.0
# Runs inside the systemd guest as the oneshot weedspray-vm-test.service (root), after
# multi-user.target: the weedspray .deb is installed, udev and the system bus run.
#
# Makes the hardware (gpio-sim chip, interrupt-cnt counter, vivid camera, IIO dummy ADC + DAC),
# writes a conf.d drop-in pointing the daemon at it, then starts the shipped weedsprayd.service
# and checks it from outside, the way an operator would (systemctl, busctl, sysfs, journalctl).
#
# Every verdict is one line on the serial console (the host greps them):
#   WEEDSPRAY-SD-CHECK <name> PASS|FAIL: <detail>
#   WEEDSPRAY-SD-INFO <text>                      measured values, shown by the host
#   WEEDSPRAY-SD-RESULT PASS|FAIL checks=N failed=M   the last line, only if the script got there
# The unit's ExecStopPost powers the guest off whatever happens here.
# Not -e (nor an ERR trap): a failed check is reported and the run goes on to the next one; the
# checks assert on status codes themselves.
set -uo pipefail

# The serial console, line by line (not through the journal): ttyS0 on x86, ttyAMA0 on arm64.
exec >"/dev/$(sed -n 's/.*console=\([^ ,]*\).*/\1/p' /proc/cmdline)" 2>&1
export SYSTEMD_PAGER='' SYSTEMD_COLORS=0 LC_ALL=C.UTF-8

checks=0
failed=0
check() { # NAME OK(0|1) DETAIL
  checks=$((checks + 1))
  if [ "$2" -eq 0 ]; then
    echo "WEEDSPRAY-SD-CHECK $1 PASS: $3"
  else
    echo "WEEDSPRAY-SD-CHECK $1 FAIL: $3"
    failed=$((failed + 1))
  fi
}
info() { echo "WEEDSPRAY-SD-INFO $*"; }
finish() {
  local verdict=PASS
  [ "$failed" -eq 0 ] || verdict=FAIL
  echo "WEEDSPRAY-SD-RESULT $verdict checks=$checks failed=$failed"
  exit 0
}
setup_failed() {
  check setup 1 "$*"
  finish
}

info "kernel $(uname -r), systemd $(systemctl --version | head -n1 | cut -d' ' -f2), boot to test $(cut -d' ' -f1 /proc/uptime) s"

# --- hardware --------------------------------------------------------------------------------
modprobe configfs || setup_failed "modprobe configfs"
mountpoint -q /sys/kernel/config || mount -t configfs configfs /sys/kernel/config ||
  setup_failed "cannot mount configfs"
modprobe gpio-sim || setup_failed "modprobe gpio-sim"

# shellcheck source=../vm/gpio-sim-chip.sh
. "$(dirname "$0")/gpio-sim-chip.sh" # make_gpio_sim_chip
# One chip holds every line the daemon drives or reads ([gpio] chip), as on a board.
gpio_lines=(valve0 valve1 valve2 valve3 pump buzzer lamp key flow wheel heartbeat estop)
make_gpio_sim_chip weedspray "${gpio_lines[@]}"
sim_dir="/sys/kernel/config/gpio-sim/weedspray"
gpio_chip="$(cat "$sim_dir/bank0/chip_name")"
line_dir="/sys/devices/platform/$(cat "$sim_dir/dev_name")/$gpio_chip"
line_value() { cat "$line_dir/sim_gpio$1/value"; } # OFFSET: what the consumer drives
set_pull() { echo "$2" >"$line_dir/sim_gpio$1/pull"; } # OFFSET pull-up|pull-down
# The flow meter counted in the kernel: interrupt-cnt on its own chip's line (test-only fixture:
# x86 has no device tree to bind it).
make_gpio_sim_chip weedspray-count flow_fast
# The fixture binds a driver that must already be loaded (no symbol dependency between them).
modprobe interrupt-cnt && modprobe interrupt_counter_fixture chip_label=weedspray-count line=0 ||
  setup_failed "modprobe interrupt_counter_fixture (loads interrupt-cnt)"
modprobe vivid n_devs=1 node_types=0x1 || setup_failed "modprobe vivid"
modprobe iio_dummy || setup_failed "modprobe iio_dummy (industrialio-sw-device, -configfs)"
iio_name=weedspray-iio
mkdir "/sys/kernel/config/iio/devices/dummy/$iio_name" ||
  setup_failed "cannot instantiate the IIO dummy through configfs"
udevadm settle --timeout=30 || setup_failed "udevadm settle timed out"

iio_dir=""
for dir in /sys/bus/iio/devices/iio:device*; do
  [ "$(cat "$dir/name" 2>/dev/null)" = "$iio_name" ] && iio_dir="$(readlink -f "$dir")" && break
done
[ -n "$iio_dir" ] || setup_failed "no IIO device named $iio_name"
counter_dir=""
for dir in /sys/bus/counter/devices/counter*; do
  [ "$(cat "$dir/name" 2>/dev/null)" = interrupt-cnt ] && counter_dir="$dir" && break
done
[ -n "$counter_dir" ] || setup_failed "no counter named interrupt-cnt"
video_node=""
for node in /dev/video*; do [ -c "$node" ] && video_node="$node" && break; done
[ -n "$video_node" ] || setup_failed "vivid made no /dev/video* node"
# vivid stamps the end of a frame by default (in the future); cameras stamp its start.
v4l2-ctl -d "$video_node" -c timestamp_source=1 || setup_failed "cannot set vivid's timestamp_source"
dac="$iio_dir/out_voltage0_raw"
info "fixtures: gpio-sim $gpio_chip (${gpio_lines[*]}), IIO $iio_name at $iio_dir, $(basename "$counter_dir") interrupt-cnt, vivid $video_node"

# --- what the packaging gave the hardware ----------------------------------------------------
perm() { stat -c '%U:%G %a' "$1"; }
check sysusers_groups "$(getent group gpio iio >/dev/null; echo $?)" \
  "$(getent group gpio iio | cut -d: -f1,3 | tr '\n' ' ')"
check udev_gpiochip "$([ "$(perm "/dev/$gpio_chip")" = "root:gpio 660" ]; echo $?)" \
  "/dev/$gpio_chip $(perm "/dev/$gpio_chip")"
check udev_iio_dac_attribute "$([ "$(perm "$dac")" = "root:iio 664" ]; echo $?)" \
  "out_voltage0_raw $(perm "$dac") (in_voltage0_raw $(perm "$iio_dir/in_voltage0_raw"))"
check udev_counter_enabled "$([ "$(cat "$counter_dir/count0/enable")" = 1 ]; echo $?)" \
  "$counter_dir/count0/enable = $(cat "$counter_dir/count0/enable")"
info "video $video_node $(perm "$video_node")"

# --- which /sys hardening lets user weedspray write the DAC ----------------------------------
# The same user, groups and /sys protection as the unit, one transient service each; the DAC is
# left at 100 so the daemon's own safe value is seen below.
dac_write_as_service() { # PROPERTY...: 0 when the write went through
  systemd-run --quiet --wait --pipe --service-type=exec -p User=weedspray -p Group=weedspray \
    -p SupplementaryGroups=iio "$@" /bin/sh -c "echo 100 >'$dac'" 2>&1 | sed 's/^/    /'
  return "${PIPESTATUS[0]}"
}
dac_write_as_service -p ProtectKernelTunables=yes
rc=$?
check sysfs_readonly_without_readwritepaths "$([ "$rc" -ne 0 ]; echo $?)" \
  "ProtectKernelTunables=yes alone refuses the DAC write (why the unit needs ReadWritePaths=)"
dac_write_as_service -p ProtectKernelTunables=no
check sysfs_writable_without_protection "$?" \
  "ProtectKernelTunables=no (the other way out) lets group iio write the DAC"
dac_write_as_service -p ProtectKernelTunables=yes -p ReadWritePaths=/sys/bus/iio/devices
info "ProtectKernelTunables=yes ReadWritePaths=/sys/bus/iio/devices: DAC write status $? (0 = written)"
dac_write_as_service -p ProtectKernelTunables=yes -p ReadWritePaths=/sys/devices
check sysfs_writable_with_readwritepaths "$?" \
  "ProtectKernelTunables=yes ReadWritePaths=/sys/devices lets group iio write the DAC"
dac_write_as_service -p ProtectKernelTunables=yes -p ReadWritePaths=/sys/devices \
  -p SupplementaryGroups=
rc=$?
check dac_needs_group_iio "$([ "$rc" -ne 0 ]; echo $?)" \
  "without group iio the same write is refused (file mode, not the mount, is the gate)"
info "DAC before the daemon starts: $(cat "$dac")"
# The unit's other risk: a supplementary group that does not exist fails the unit (216/GROUP),
# which is why sysusers.d makes gpio and iio.
systemd-run --quiet --wait -p User=weedspray -p SupplementaryGroups=weedspray-no-such-group \
  /bin/true >/dev/null 2>&1
rc=$?
check missing_group_fails_unit "$([ "$rc" -ne 0 ]; echo $?)" \
  "SupplementaryGroups= naming a missing group: systemd-run status $rc"
info "shipped unit: $(systemctl show weedsprayd -p ProtectKernelTunables -p ReadWritePaths \
  -p SupplementaryGroups -p ProtectSystem -p DevicePolicy | tr '\n' ' ')"

# --- configuration -------------------------------------------------------------------------------
full_scale_v=3.3
dac_scale_mv=1.0 # iio_dummy's DAC channel has no out_voltage0_scale
cat >/etc/weedspray/conf.d/50-vm-test.toml <<EOF
# Written by tests/vm-systemd/guest-test.sh: the guest's simulated hardware.
[gpio]
chip = "weedspray"
valve_names = ["valve0", "valve1", "valve2", "valve3"]
pump_name = "pump"
buzzer_name = "buzzer"
led_name = "lamp"
key_name = "key"
key_active_low = false
wheel_name = "wheel"
heartbeat_name = "heartbeat"
# The E-stop circuit, closed: gpio-sim's default pull-down holds the line low.
estop_name = "estop"

[flow]
counter = "interrupt-cnt"

[adc]
iio_device = "$iio_name"
pressure_channel = 0

[dac]
iio_device = "$iio_name"
channel = 0
full_scale_v = $full_scale_v
iio_scale_mv = $dac_scale_mv
EOF
# A drop-in cannot change an [[camera]] entry, so the main file's camera is edited in place;
# a small frame keeps the emulated CPU's vision thread in time.
sed -i -e "/^\[\[camera\]\]/,\$ { s#^device = .*#device = '$video_node'#; s/^width = .*/width = 320/; s/^height = .*/height = 180/; s/^fps = .*/fps = 10.0/ }" \
  /etc/weedspray/weedspray.toml
out="$(weedsprayd --check-config 2>&1)"
check config_valid "$?" "weedsprayd --check-config: $(echo "$out" | tail -n1)"
# Safe = return valve fully open = DAC at full scale (backends_hw_converters.cpp); the driver
# takes raw = round(volts * 1000 / mV per count), clamped to the 12-bit range.
expected_raw="$(awk -v v="$full_scale_v" -v s="$dac_scale_mv" \
  'BEGIN { r = int(v * 1000 / s + 0.5); if (r > 4095) r = 4095; print r }')"

# --- the daemon under its shipped unit ---------------------------------------------------------
# A free gpio-sim line reads its pull. Pulled up, the valve and pump lines read 1 until the
# daemon requests them; reading 0 afterwards shows the daemon drives them low.
for offset in 0 1 2 3 4; do set_pull "$offset" pull-up; done
free_values="$(for offset in 0 1 2 3 4; do line_value "$offset"; done | tr -d '\n')"
check outputs_pulled_up_before "$([ "$free_values" = 11111 ]; echo $?)" \
  "valve0..3 and pump lines, free and pulled up, read $free_values"
started=$(date +%s.%N)
out="$(timeout 90 systemctl start weedsprayd 2>&1)"
status=$?
info "systemctl start weedsprayd took $(awk -v a="$started" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }') s"
check unit_start "$status" "systemctl start weedsprayd (Type=notify) ${out:-returned}"
active="$(systemctl is-active weedsprayd)"
check unit_active "$([ "$active" = active ]; echo $?)" "is-active: $active"

bus_get() { busctl get-property org.weedspray.Sprayer1 /org/weedspray/Sprayer1 org.weedspray.Sprayer1 "$1" 2>&1; }
mode="$(bus_get Mode)"
check dbus_mode_hw "$([ "$mode" = 's "hw"' ]; echo $?)" "Mode = $mode"
state="$(bus_get State)"
check dbus_state_readable "$([[ "$state" == 's "'* ]]; echo $?)" "State = $state"

main_pid="$(systemctl show -p MainPID --value weedsprayd)"
uid="$(awk '/^Uid:/ { print $2 }' "/proc/$main_pid/status" 2>/dev/null)"
user="$(getent passwd "${uid:-x}" | cut -d: -f1)"
groups="$(for g in $(awk '/^Groups:/ { $1 = ""; print }' "/proc/$main_pid/status" 2>/dev/null); do getent group "$g" | cut -d: -f1; done | tr '\n' ' ')"
check runs_as_weedspray "$([ "$user" = weedspray ]; echo $?)" \
  "MainPID $main_pid user ${user:-?} groups ${groups:-?}"

dac_raw="$(cat "$dac")"
check dac_safe_at_start "$([ "$dac_raw" = "$expected_raw" ]; echo $?)" \
  "out_voltage0_raw = $dac_raw, expected $expected_raw ($full_scale_v V / $dac_scale_mv mV per count: return valve fully open)"

outputs_safe() { # -> "valve0=0 ... pump=0"; status 0 when all read 0
  local i text="" bad=0 v
  for i in 0 1 2 3 4; do
    v="$(line_value "$i")"
    text="$text${gpio_lines[$i]}=$v "
    [ "$v" = 0 ] || bad=1
  done
  echo "$text"
  return "$bad"
}
text="$(outputs_safe)"
check outputs_safe_running "$?" "gpio-sim lines: $text"

# Let the loops run (and the watchdog, 2 s) before judging the steady state.
sleep 8
active="$(systemctl is-active weedsprayd)"
check unit_still_active "$([ "$active" = active ]; echo $?)" \
  "is-active after 8 s: $active (NRestarts=$(systemctl show -p NRestarts --value weedsprayd))"
for property in State Pressure Alarms Flow FrameRate ControlOverruns; do
  info "D-Bus $property = $(bus_get "$property")"
done
info "buzzer=$(line_value 5) lamp=$(line_value 6); ADC in_voltage0_raw=$(cat "$iio_dir/in_voltage0_raw") scale=$(cat "$iio_dir/in_voltage0_scale") mV"
text="$(outputs_safe)"
check outputs_safe_idle "$?" "gpio-sim lines after 8 s: $text"
check dac_safe_idle "$([ "$(cat "$dac")" = "$expected_raw" ]; echo $?)" "out_voltage0_raw = $(cat "$dac")"

# An operator (group weedspray, not root) reads the status with sprayctl.
useradd --system --no-create-home --gid weedspray operator 2>/dev/null || true
out="$(setpriv --reuid=operator --regid=weedspray --init-groups sprayctl status 2>&1)"
status=$?
echo "$out" | sed 's/^/    sprayctl: /'
check sprayctl_status_as_operator "$status" "sprayctl status as user operator (group weedspray)"

# The live view in hardware mode, as the operator: the daemon (user weedspray) sends the PNG of
# vivid's next frame over the system bus, sprayctl (the operator) writes it. PNG signature and
# the IHDR's width and height (bytes 16..23, big-endian) = the camera's 320x180.
out="$(cd /tmp && setpriv --reuid=operator --regid=weedspray --init-groups sprayctl snapshot /tmp/live-view.png 2>&1)"
status=$?
header="$(od -An -tx1 -N8 /tmp/live-view.png 2>/dev/null | tr -d ' \n')"
size="$(od -An -tu1 -j16 -N8 /tmp/live-view.png 2>/dev/null | tr -s ' ' | sed 's/^ //')"
check snapshot_as_operator "$([ "$status" = 0 ] && [ "$header" = 89504e470d0a1a0a ] &&
  [ "$size" = "0 0 1 64 0 0 0 180" ]; echo $?)" \
  "sprayctl snapshot: ${out:-?}; PNG header $header, IHDR width/height bytes '$size' (320x180: 0 0 1 64 0 0 0 180)"

# --- stop -------------------------------------------------------------------------------------
# Released lines read their pull again; pulled down, as a board's valve drivers are, so the
# lines stay off once the daemon has let go of them.
for offset in 0 1 2 3 4; do set_pull "$offset" pull-down; done
was_active="$(systemctl is-active weedsprayd)"
out="$(timeout 30 systemctl stop weedsprayd 2>&1)"
check unit_stop "$?" "systemctl stop weedsprayd ${out:-returned}"
result="$(systemctl show -p Result --value weedsprayd)"
state="$(systemctl is-active weedsprayd)"
safe_line="$(journalctl -u weedsprayd -b --no-pager -q -o cat | grep -c '^outputs safe: ')"
check stop_clean "$([ "$was_active" = active ] && [ "$result" = success ] && [ "$state" = inactive ] &&
  [ "$safe_line" -ge 1 ]; echo $?)" \
  "was $was_active, now $state, Result=$result, 'outputs safe' journal lines: $safe_line"
text="$(outputs_safe)"
check outputs_safe_stopped "$?" "gpio-sim lines after stop (released, pulled down): $text"
check dac_safe_stopped "$([ "$(cat "$dac")" = "$expected_raw" ]; echo $?)" "out_voltage0_raw = $(cat "$dac")"

# --- the journal ------------------------------------------------------------------------------
echo "    ---- journalctl -u weedsprayd ----"
journalctl -u weedsprayd -b --no-pager -o short-monotonic | sed 's/^/    /'
echo "    ---- end of journal ----"
# Error lines, except the one the hardware makes honestly: iio_dummy's ADC reads a fixed
# 73 x 0.001333 mV, far below a 4 mA loop, so a pressure sensor fault is raised (pump off,
# valves closed). Anything else at priority err or worse fails.
expected_errors=('^alarm raised: pressure_sensor_fault \(fault: valves closed, pump off; loop current [0-9.]+ mA\)$')
# The guest runs under TCG (aarch64: 3-5x slower again than x86): the loops miss their periods
# by up to 0.5 s on arm64, and by tens of ms on x86 when the host is busy, and the cross-watch
# then reports the valve thread stalled (and makes the outputs safe, as it must). The host says
# so on the kernel command line; the lines are counted below. Any other error line still fails.
if grep -q 'weedspray.tcg_stalls_expected=1' /proc/cmdline; then
  expected_errors+=('^valve thread stalled: pump off and return valve open until it runs again$')
  info "cross-watch stall lines (emulation, tolerated): $(journalctl -u weedsprayd -b --no-pager -q -p err -o cat | grep -c '^valve thread stalled: ')"
fi
errors="$(journalctl -u weedsprayd -b --no-pager -q -p err -o cat |
  grep -vE "$(IFS='|'; echo "${expected_errors[*]}")" || true)"
check journal_no_errors "$([ -z "$errors" ]; echo $?)" \
  "priority err lines besides the sensor-fault alarm: ${errors:-none}"
info "journal err lines (all): $(journalctl -u weedsprayd -b --no-pager -q -p err -o cat | tr '\n' '|')"
# That alarm's entry carries its catalog MESSAGE_ID, and the package's catalog is indexed (the
# systemd package's trigger ran journalctl --update-catalog), so journalctl -x explains it.
sensor_id=6f28571a2c6746e198c507f3265366f3
catalogued="$(journalctl -u weedsprayd -b --no-pager -q -x MESSAGE_ID="$sensor_id" -o short | grep -c 'What to do: Check the sensor' || true)"
check alarm_catalog_in_journal "$([ "${catalogued:-0}" -ge 1 ]; echo $?)" \
  "journalctl -x entries of pressure_sensor_fault with the catalog's remedy: $catalogued; catalog: $(journalctl --list-catalog 2>/dev/null | grep -c 'weedspray: alarm') weedspray entries"

# The installed man pages open with man(1), each showing its NAME line.
man_shown=""
man_missing=""
for page in 8:weedsprayd 1:sprayctl 5:weedspray.toml 8:weedspray-safe-outputs; do
  # The whole page is read before it is searched: a reader that stops at the NAME line would
  # end man's pipeline early (SIGPIPE), which pipefail reports as a failure.
  shown="$(MANPAGER=cat MANWIDTH=100 man "${page%%:*}" "${page#*:}" 2>/dev/null)"
  if grep -qE "^ +${page#*:} +- " <<<"$shown"; then
    man_shown+=" ${page#*:}(${page%%:*})"
  else
    man_missing+=" ${page#*:}(${page%%:*})"
  fi
done
check man_pages "$([ -z "$man_missing" ]; echo $?)" \
  "man shows:${man_shown:- none}; missing or without a NAME line:${man_missing:- none}"

finish
