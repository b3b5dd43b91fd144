#!/bin/bash
# SPDX-License-Identifier: Apache-2.0
# Hardware in the loop, run in the systemd guest after guest-test.sh (same unit, as
# root). weedspray-hil plays the sprayer behind the wires (tools/hil): it samples the valve,
# pump, buzzer, lamp and heartbeat lines of the gpio-sim chip guest-test.sh made, pulses the
# flow meter (interrupt-cnt chip) and wheel lines, writes the pressure transmitter's voltage
# into the IIO dummy's ADC input and reads the return valve's voltage from its DAC output (the
# device guest-test.sh made), and serves the tank level as a Modbus RTU slave on a pty, all
# driven by the hydraulic plant model. The installed weedsprayd.service runs against it with
# [adc]/[dac] source = "iio" (as a Pi with an ADS1115 and an MCP4725) and [modbus] for the tank.
#
# Safety figures come from the kernel's own record: tracefs events gpio_value (every value
# written to a line, by anyone, with its time), signal_generate (the fatal signal: kill -9,
# abort, SIGSEGV, the watchdog's SIGABRT) and sched_process_exit. A line keeps the value last
# written to it, as a board's output latch does when a process lets go of it (gpio-sim itself
# falls back to its pull on release, which would hide an unsafe exit): so "unsafe" is the time
# from the fatal signal until every valve and the pump have been written 0, and a daemon whose
# fail-safe paths do nothing stays unsafe until its restart writes them.
#
# Prints WEEDSPRAY-HIL-STEP name PASS|FAIL: detail, WEEDSPRAY-HIL key=value figures and, last,
# WEEDSPRAY-HIL-RESULT PASS|FAIL steps=N failed=M on the serial console.
set -uo pipefail

# The serial console, line by line (not through the journal): ttyS0 on x86, ttyAMA0 on arm64.
exec >"/dev/$(sed -n 's/.*console=\([^ ,]*\).*/\1/p' /proc/cmdline)" 2>&1
export SYSTEMD_PAGER='' SYSTEMD_COLORS=0 LC_ALL=C.UTF-8
# Only when the host asked for it (run-systemd-vm-test.sh --hil): it is not in ./dev test yet.
if ! grep -qE 'weedspray\.hil(_selftest)?=1' /proc/cmdline; then
  echo "WEEDSPRAY-HIL skipped (no weedspray.hil=1 on the kernel command line)"
  exit 0
fi

steps_passed=0
steps_failed=0
step() { # NAME OK(0|1) DETAIL
  if [ "$2" -eq 0 ]; then
    echo "WEEDSPRAY-HIL-STEP $1 PASS: $3"
    steps_passed=$((steps_passed + 1))
  else
    echo "WEEDSPRAY-HIL-STEP $1 FAIL: $3"
    steps_failed=$((steps_failed + 1))
  fi
}
figure() { echo "WEEDSPRAY-HIL $1=$2"; }
info() { echo "WEEDSPRAY-HIL-INFO $*"; }
finish() {
  [ -n "${hil_pid:-}" ] && { echo quit >"$run_dir/control"; wait "$hil_pid"; }
  figure steps_passed "$steps_passed"
  figure steps_failed "$steps_failed"
  local verdict=PASS
  [ "$steps_failed" -eq 0 ] || verdict=FAIL
  echo "WEEDSPRAY-HIL-RESULT $verdict steps=$((steps_passed + steps_failed)) failed=$steps_failed"
  exit 0
}
setup_failed() {
  step setup 1 "$*"
  finish
}
now() { cut -d' ' -f1 /proc/uptime; } # CLOCK_BOOTTIME, fine for step durations
elapsed() { awk -v a="$1" -v b="$(now)" 'BEGIN { printf "%.2f", b - a }'; }

# --- the hardware guest-test.sh made -----------------------------------------------------------
sim_dir=/sys/kernel/config/gpio-sim/weedspray
count_dir=/sys/kernel/config/gpio-sim/weedspray-count
[ -d "$sim_dir" ] && [ -d "$count_dir" ] || setup_failed "guest-test.sh made no gpio-sim chips"
chip_dir="/sys/devices/platform/$(cat "$sim_dir/dev_name")/$(cat "$sim_dir/bank0/chip_name")"
flow_chip_dir="/sys/devices/platform/$(cat "$count_dir/dev_name")/$(cat "$count_dir/bank0/chip_name")"
# Offsets as guest-test.sh names them: valve0..3 pump buzzer lamp key flow wheel heartbeat
# estop.
valve_lines=(0 1 2 3)
pump_line=4
counter_dir=""
for dir in /sys/bus/counter/devices/counter*; do
  [ "$(cat "$dir/name" 2>/dev/null)" = interrupt-cnt ] && counter_dir="$dir" && break
done
[ -n "$counter_dir" ] || setup_failed "no interrupt-cnt counter"
gpio_base=""
for dir in /sys/class/gpio/gpiochip*; do
  [ "$(cat "$dir/label" 2>/dev/null)" = weedspray ] && gpio_base="$(cat "$dir/base")" && break
done
[ -n "$gpio_base" ] || setup_failed "no /sys/class/gpio entry labelled weedspray (GPIO base)"
# The IIO dummy guest-test.sh instantiated: its in_voltage0_raw takes the plant's writes
# (tests/vm/iio_dummy_settable_adc.patch), its out_voltage0_raw holds the daemon's DAC writes.
iio_name=weedspray-iio
iio_dir=""
for dir in /sys/bus/iio/devices/iio:device*; do
  [ "$(cat "$dir/name" 2>/dev/null)" = "$iio_name" ] && iio_dir="$(readlink -f "$dir")" && break
done
[ -n "$iio_dir" ] || setup_failed "no IIO device named $iio_name"
# Millivolts per count, the daemon's iio_scale_mv and the plant's alike: the ADC as an ADS1115
# at +-4.096 V (the dummy's own in_voltage0_scale, 0.001333 mV, would need 2.5 million counts
# for 3.3 V); the DAC as guest-test.sh sets it (the dummy has no out_voltage0_scale).
adc_scale_mv=0.125
dac_scale_mv=1.0
watched="$(for l in "${valve_lines[@]}" "$pump_line"; do printf '%d ' $((gpio_base + l)); done)"
# The camera: field images through v4l2loopback when the host made them (x86: run-systemd-vm-
# test.sh, weedspray-lab hil-frames); weedspray-hil writes them. Else vivid, every zone green
# (its "100% Green" pattern, without the on-screen text, which made the zones' densities differ
# and move): the daemon sees weeds everywhere and sprays.
frames_dir=/usr/local/share/weedspray-hil/frames
camera_args=()
if [ -f "$frames_dir/truth.txt" ]; then
  modprobe v4l2loopback video_nr=20 card_label=weedspray-loopback exclusive_caps=1 ||
    setup_failed "modprobe v4l2loopback"
  video_node=/dev/video20
  camera_args=(--camera-device "$video_node" --camera-frames "$frames_dir" --camera-frame field
    --camera-width 320 --camera-height 180 --camera-fps 2)
  figure camera loopback
else
  video_node="$(ls /dev/video* | head -n1)"
  v4l2-ctl -d "$video_node" -c test_pattern=8 -c osd_text_mode=2 || setup_failed "cannot set vivid's test pattern"
  figure camera vivid
fi

tracing=/sys/kernel/tracing
mountpoint -q "$tracing" || mount -t tracefs tracefs "$tracing" || setup_failed "no tracefs"
[ -d "$tracing/events/gpio/gpio_value" ] || setup_failed "no gpio_value trace event"
echo mono >"$tracing/trace_clock"
echo 4096 >"$tracing/buffer_size_kb"
echo 'get == 0' >"$tracing/events/gpio/gpio_value/filter" # writes only
for event in gpio/gpio_value signal/signal_generate sched/sched_process_exit; do
  echo 1 >"$tracing/events/$event/enable" || setup_failed "cannot enable trace event $event"
done

# --- the simulated machine -----------------------------------------------------------------------
run_dir=/run/weedspray-hil
hil_log=/run/weedspray-hil.log
weedspray-hil --chip-dir "$chip_dir" --valve-lines "${valve_lines[@]}" --pump-line "$pump_line" \
  --buzzer-line 5 --lamp-line 6 --heartbeat-line 10 --wheel-line 9 \
  --flow-chip-dir "$flow_chip_dir" --flow-line 0 --run-dir "$run_dir" --rate-hz 2000 \
  --iio-dir "$iio_dir" --adc-mv-per-count "$adc_scale_mv" --dac-mv-per-count "$dac_scale_mv" \
  --tank-capacity-l 200 --tank-level-l 150 --wheel-pulses-per-m 20 --flow-pulses-per-l 2000 \
  --seed 11 "${camera_args[@]}" >"$hil_log" 2>&1 &
hil_pid=$!
for _ in $(seq 50); do [ -p "$run_dir/control" ] && [ -f "$run_dir/status" ] && break; sleep 0.1; done
[ -f "$run_dir/status" ] || { cat "$hil_log"; setup_failed "weedspray-hil did not start"; }
hil() { sed -n "s/^$1=//p" "$run_dir/status"; } # KEY: the plant's latest status value
hil_command() { echo "$*" >"$run_dir/control"; }
counter_count() { cat "$counter_dir/count0/count"; }
flow_count_before="$(counter_count)"

# --- the daemon, wired to it by a conf.d drop-in -------------------------------------------------
systemctl stop weedsprayd 2>/dev/null
rm -f /etc/weedspray/conf.d/50-vm-test.toml
cat >/etc/weedspray/conf.d/50-hil.toml <<EOF
# Written by tests/vm-systemd/hil-scenario.sh: the machine is weedspray-hil.
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
# The E-stop circuit: closed while the line reads low (gpio-sim's pull-down); the step
# estop_safe pulls it up, as a pressed button or a cut wire lets the board's pull-up do.
estop_name = "estop"

[flow]
counter = "interrupt-cnt"
# A coarser meter than the LWGY's 8500/L: weedspray-hil makes one edge per sample, and the
# emulated CPU samples at well under 2 kHz when busy.
pulses_per_litre = 2000

# The pressure loop runs at its default 100 Hz with the default gains: the ADC and DAC are
# sysfs attributes of the IIO dummy, one pread or pwrite each, as an ADS1115 and an
# MCP4725 are on a Pi (the plant updates the ADC input and reads the DAC at 500 Hz).

# The plant's wheel: 20 magnets a metre, so the wheel's edges are 40 ms apart at 0.6 m/s (the
# kernel's threaded edge handler merges edges closer than it gets the emulated CPU).
[wheel]
pulses_per_metre = 20

$([ "$video_node" = /dev/video20 ] || printf '%s\n' '# vivid: one colour, no histogram to split.' '[vision]' 'threshold = "fixed"')

[adc]
source = "iio"
iio_device = "$iio_name"
pressure_channel = 0
iio_scale_mv = $adc_scale_mv

[dac]
source = "iio"
iio_device = "$iio_name"
channel = 0
full_scale_v = 3.3
iio_scale_mv = $dac_scale_mv

# The tank level: a Modbus RTU module on its own bus (a pty of weedspray-hil).
[modbus]
enabled = true
device = "$run_dir/tank"
poll_period_s = 0.2
EOF
# 2 frames a second leave the emulated CPUs time for the loops (camera_stall_s is 1 s). A
# drop-in cannot change an [[camera]] entry: the main file's is edited (as guest-test.sh does).
sed -i -e "/^\[\[camera\]\]/,\$ { s/^fps = .*/fps = 2.0/; s#^device = .*#device = '$video_node'# }" \
  /etc/weedspray/weedspray.toml
# Test-only: the pty (char-pts) behind the tank's Modbus port, and the crash hook's variable.
mkdir -p /etc/systemd/system/weedsprayd.service.d
cat >/etc/systemd/system/weedsprayd.service.d/50-hil.conf <<EOF
[Service]
DeviceAllow=char-pts rw
Environment=WEEDSPRAY_TEST_CRASH_HOOK=1
EOF
if grep -q 'weedspray.hil_selftest=1' /proc/cmdline; then
  # Harness self-test: the package was built with WEEDSPRAY_SELFTEST_NO_FAILSAFE; take the
  # unit's ExecStopPost away as well. Every safety step below must now fail.
  printf '[Service]\nExecStopPost=\n' >/etc/systemd/system/weedsprayd.service.d/60-no-failsafe.conf
  info "self-test: ExecStopPost removed, package built without fail-safe paths"
fi
systemctl daemon-reload

bus_get() { busctl get-property org.weedspray.Sprayer1 /org/weedspray/Sprayer1 org.weedspray.Sprayer1 "$1" 2>/dev/null; }
bus_value() { bus_get "$1" | cut -d' ' -f2-; } # without the type letter
bus_state() { bus_get State | sed 's/^s "\(.*\)"$/\1/'; }
main_pid() { systemctl show -p MainPID --value weedsprayd; }
wait_for() { # SECONDS COMMAND...: until COMMAND succeeds
  local deadline=$(($(date +%s) + $1))
  shift
  until "$@"; do
    [ "$(date +%s)" -lt "$deadline" ] || return 1
    sleep 0.2
  done
}
state_is() { [ "$(bus_state)" = "$1" ]; }
active_with_new_pid() { [ "$(systemctl is-active weedsprayd)" = active ] && [ "$(main_pid)" != "$1" ] && [ "$(main_pid)" != 0 ]; }
start_spraying() { # -> 0 when Spraying with the pump on
  # Each fault step needs a spraying daemon: one latched in Fault by an earlier step (that step
  # has failed already and says why) is restarted first, so the next step still measures.
  if state_is Fault; then
    info "State=Fault (Alarms $(bus_value Alarms); $(journalctl -u weedsprayd -b -p err -o cat | tail -n 3 | tr '\n' '|')): systemctl restart weedsprayd"
    timeout 90 systemctl restart weedsprayd
    wait_for 30 state_is Idle
  fi
  sprayctl start >/dev/null 2>&1
  wait_for 30 state_is Spraying && sleep 2 && wait_for 10 sh -c "grep -qx pump=1 $run_dir/status"
}

out="$(weedsprayd --check-config 2>&1)"
step config_valid "$?" "$(echo "$out" | tail -n1)"
started="$(now)"
timeout 90 systemctl start weedsprayd
step unit_start "$?" "systemctl start weedsprayd in $(elapsed "$started") s ($(systemctl is-active weedsprayd))"

# --- Idle with live readings --------------------------------------------------------------------
wait_for 10 state_is Idle
state="$(bus_state)"
pressure="$(bus_value Pressure)"
tank="$(bus_value TankLevel)"
true_tank="$(hil tank_pct)"
ok="$(awk -v s="$state" -v p="$pressure" -v t="$tank" -v tt="$true_tank" \
  'BEGIN { print (s == "Idle" && p != "" && t != "" && (t - tt) ^ 2 < 1) ? 0 : 1 }')"
step idle_live_readings "$ok" "State=$state Pressure=$pressure MPa (plant $(hil pressure_mpa) MPa, IIO ADC in_voltage0_raw $(cat "$iio_dir/in_voltage0_raw") after $(hil adc_writes) plant writes) TankLevel=$tank % (plant $true_tank %, Modbus requests $(hil tank_requests)), IIO DAC $(hil dac_volts) V (out_voltage0_raw $(cat "$iio_dir/out_voltage0_raw")), plant IIO errors $(hil iio_errors)"

# --- spraying: pressure and duty -----------------------------------------------------------------
hil_command speed 0.6
sleep 1
start_spraying
started_ok=$?
step start_spraying "$started_ok" "sprayctl start: State=$(bus_state), pump line $(hil pump), Alarms $(bus_value Alarms)"
# That step has failed (and says why); the pressure and duty below still need a spraying daemon.
[ "$started_ok" -eq 0 ] || { sleep 1; start_spraying || info "still not spraying: State=$(bus_state)"; }
setpoint="$(bus_value PressureSetpoint)"
sleep 10 # the pressure loop settles (about 2 s on the plant; the emulated CPU is slower)
samples=()
daemon_samples=()
dac_samples=()
for _ in $(seq 10); do
  samples+=("$(hil pressure_mpa)")
  dac_samples+=("$(hil dac_volts)")
  daemon_samples+=("$(bus_value Pressure)")
  sleep 0.2
done
daemon_mean="$(printf '%s\n' "${daemon_samples[@]}" | awk '{ s += $1 } END { printf "%.4f", s / NR }')"
pressure="$(printf '%s\n' "${samples[@]}" | awk '{ s += $1 } END { printf "%.4f", s / NR }')"
spread="$(printf '%s\n' "${samples[@]}" | awk -v sp="$setpoint" '{ d = $1 - sp; if (d < 0) d = -d; if (d > m) m = d } END { printf "%.4f", m }')"
figure pressure_mpa "$pressure"
figure setpoint_mpa "$setpoint"
ok="$(awk -v p="$pressure" -v s="$setpoint" 'BEGIN { d = p - s; if (d < 0) d = -d; print (s > 0 && d <= 0.02) ? 0 : 1 }')"
info "pressure reads (plant | daemon | return-valve DAC V): ${samples[*]} | ${daemon_samples[*]} | ${dac_samples[*]}"
step pressure_at_setpoint "$ok" "plant's line pressure mean of 10 reads over 2 s $pressure MPa, set-point $setpoint, worst read off by $spread; the daemon's Pressure, same reads: mean $daemon_mean"

# Measured duty per line over a window vs the daemon's NozzleDuty (read at both ends: it must
# not change in between, or the window is not one duty).
# The same window from the kernel's record: each valve line's share of time written 1 (exact edge
# times, no sampling), as a cross-check of the sampler.
trace_duty() { # -> "d0 d1 d2 d3" in percent over the traced span
  echo 0 >"$tracing/tracing_on"
  awk -v base="$gpio_base" -v init="$(hil valve_mask)" '
    BEGIN { for (i = 0; i < 4; i++) state[i] = int(init / 2 ^ i) % 2; first = -1 }
    / gpio_value: / {
      for (i = 1; i <= NF; i++) if ($i ~ /^[0-9]+\.[0-9]+:$/) ts = substr($i, 1, length($i) - 1) + 0
      for (i = 1; i <= NF; i++) if ($i == "gpio_value:") { l = $(i + 1) - base; v = $(i + 3) }
      if (l < 0 || l > 3) next
      if (first < 0) { first = ts; for (k = 0; k < 4; k++) since[k] = ts }
      if (state[l] == 1) open[l] += ts - since[l]
      # Where a difference comes from: each pulse (rise to fall) and period (rise to rise).
      if (state[l] == 0 && v == 1) { if (rose[l] > 0) { p = ts - rose[l]; periods[l]++; psum[l] += p; if (p > pmax[l]) pmax[l] = p; if (pmin[l] == 0 || p < pmin[l]) pmin[l] = p }; rose[l] = ts }
      if (state[l] == 1 && v == 0 && rose[l] > 0) { o = ts - rose[l]; pulses[l]++; osum[l] += o; if (o > omax[l]) omax[l] = o; if (omin[l] == 0 || o < omin[l]) omin[l] = o }
      state[l] = v; since[l] = ts; last = ts
    }
    END {
      for (k = 0; k < 4; k++) { if (state[k] == 1) open[k] += last - since[k]; printf "%.2f ", (last > first) ? open[k] / (last - first) * 100 : -1 }
      printf "%.6f %.6f\n", first, last > "/run/weedspray-duty-span"
      for (k = 0; k < 4; k++) if (pulses[k] > 0 && periods[k] > 0)
        printf "valve%d: %d pulses %.1f ms (%.1f-%.1f), %d periods %.1f ms (%.1f-%.1f); ", k, pulses[k], osum[k] / pulses[k] * 1000, omin[k] * 1000, omax[k] * 1000, periods[k], psum[k] / periods[k] * 1000, pmin[k] * 1000, pmax[k] * 1000 > "/run/weedspray-duty-edges"
    }' "$tracing/trace"
  echo 1 >"$tracing/tracing_on"
}
echo 0 >"$tracing/tracing_on"; echo >"$tracing/trace"; echo 1 >"$tracing/tracing_on"
duty_before="$(bus_value NozzleDuty)"
t1="$(hil sampled_s)"; open1=(); for i in 0 1 2 3; do open1+=("$(hil "valve${i}_open_s")"); done
sleep 6
t2="$(hil sampled_s)"; open2=(); for i in 0 1 2 3; do open2+=("$(hil "valve${i}_open_s")"); done
duty_after="$(bus_value NozzleDuty)"
traced="$(trace_duty)"
measured="$(for i in 0 1 2 3; do awk -v a="${open1[$i]}" -v b="${open2[$i]}" -v t1="$t1" -v t2="$t2" 'BEGIN { printf "%.2f ", (b - a) / (t2 - t1) * 100 }'; done)"
# What the daemon commanded over the same span: NozzleDuty moves with the speed estimate (the
# wheel's 20 pulses/m), by tens of points within a window on the emulated CPU, so two reads of it
# say little. The as-applied log has the commanded duty of every PWM period, stamped on
# CLOCK_MONOTONIC like the trace (trace_clock mono): its mean over the traced span, as
# "4 d1 d2 d3 d4" like NozzleDuty. (The log is fdatasync'd every second.)
sleep 1.5
read -r span_first span_last </run/weedspray-duty-span
applied_log="$(ls -t /var/lib/weedspray/as-applied/*.csv 2>/dev/null | head -n1)"
commanded="$(awk -F, -v a="$span_first" -v b="$span_last" '
  NR == 1 { for (i = 1; i <= NF; i++) if ($i ~ /^duty_pct_[0-3]$/) col[substr($i, 10) + 0] = i; next }
  $1 + 0 >= a && $1 + 0 <= b { rows++; for (k = 0; k < 4; k++) sum[k] += $(col[k]) }
  END { printf "4"; for (k = 0; k < 4; k++) printf " %.4f", rows ? sum[k] / rows : -1; printf "\n"; print rows > "/run/weedspray-duty-rows" }' "$applied_log")"
commanded_rows="$(cat /run/weedspray-duty-rows)"
# NozzleDuty prints as: 4 d1 d2 d3 d4. The figure is the kernel's record (every edge's exact
# time) against the log's commanded mean; the plant's sampling (below 2 kHz on the emulated
# CPU, with gaps) is a cross-check.
max_error() { # "m0 m1 m2 m3" "4 d1 d2 d3 d4" -> max |m - d|
  awk -v m="$1" -v d="$2" 'BEGIN { split(m, mm, " "); n = split(d, dd, " "); e = 0;
    for (i = 2; i <= n; i++) { x = mm[i - 1] - dd[i]; if (x < 0) x = -x; if (x > e) e = x }; printf "%.2f", e }'
}
duty_error="$(max_error "$traced" "$commanded")"
sampled_error="$(max_error "$measured" "$commanded")"
figure duty_error_pct_max "$duty_error"
figure duty_error_sampled_pct_max "$sampled_error"
figure sample_hz "$(hil sample_hz)"
ok="$(awk -v e="$duty_error" -v c="$commanded" -v r="$commanded_rows" \
  'BEGIN { split(c, d, " "); print (r >= 10 && d[2] > 0 && e <= 2) ? 0 : 1 }')"
info "spraying: Speed $(bus_value Speed) m/s, ZoneDensity $(bus_value ZoneDensity), FrameRate $(bus_value FrameRate), Flow $(bus_value Flow) L/min (plant $(hil nozzle_flow_l_per_min)), Alarms $(bus_value Alarms)"
info "traced valve edges: $(cat /run/weedspray-duty-edges 2>/dev/null)"
step duty_matches "$ok" "traced edges: ${traced}% vs commanded (as-applied log, mean of $commanded_rows PWM periods in the traced span $span_first-$span_last s): ${commanded#4 }%: max error $duty_error points (NozzleDuty $duty_before at the start, $duty_after at the end); sampled on the lines over $(awk -v a="$t1" -v b="$t2" 'BEGIN { printf "%.1f", b - a }') s: ${measured}% (max error $sampled_error) at $(hil sample_hz) Hz, longest gap $(hil max_gap_ms) ms"

# --- pulses: sent by the plant vs counted ---------------------------------------------------------
# The wheel stops (so do the valves and the flow): then both counts are final.
hil_command speed 0
sleep 2
flow_sent="$(hil flow_sent)"
flow_counted=$(($(counter_count) - flow_count_before))
wheel_sent="$(hil wheel_sent)"
distance="$(bus_value Distance)"
wheel_counted="$(awk -v d="$distance" 'BEGIN { printf "%.0f", d * 20 }')"
figure flow_pulses_sent "$flow_sent"
figure flow_pulses_counted "$flow_counted"
figure wheel_pulses_sent "$wheel_sent"
figure wheel_pulses_counted "$wheel_counted"
within() { awk -v s="$1" -v c="$2" 'BEGIN { d = s - c; if (d < 0) d = -d; print (s > 0 && d <= 0.005 * s) ? 0 : 1 }'; }
step flow_pulses_counted "$(within "$flow_sent" "$flow_counted")" "flow meter: plant sent $flow_sent, interrupt-cnt (the daemon's counter) counted $flow_counted"
step wheel_pulses_counted "$(within "$wheel_sent" "$wheel_counted")" "wheel: plant sent $wheel_sent, the daemon's Distance $distance m x 20 pulses/m = $wheel_counted"
hil_command speed 0.6

# --- the camera: the daemon's zones follow the field image ----------------------------------------
# Two frames of real photo tiles (truth.txt: each zone's plant cover from the photo's hand-drawn
# mask, and what the vision library's default pipeline measured on the host on the same bytes).
# Each is shown for a while; the daemon must then see a weedy zone where the mask has plants and
# a bare one where it has none (ZoneDensity above / at most the spray law's decision threshold),
# measure what the host's library measured (the V4L2 path delivered the frame intact), and spray
# the weedy zones' nozzles, not the bare ones': judged on the valve lines in the kernel's record
# over the reads (a weedy zone's valve opened at least once, a bare one's never), not on
# NozzleDuty, which is the duty of one instant (one read in a trial run was 0 for every nozzle
# while the valves went on pulsing; it is printed).
if [ "$video_node" = /dev/video20 ]; then
  decision="$(sed -n 's/^decision_threshold = //p' /etc/weedspray/weedspray.toml | head -n1)"
  camera_ok=0
  library_error=0
  details=""
  for frame in weeds-0-2 weeds-1-3; do
    hil_command frame "$frame"
    sleep 6 # 3 frames at 2 fps, then 1.2 m to the nozzles at 0.6 m/s
    read -r -a truth <<<"$(sed -n "s/^$frame cover \([^|]*\)|.*/\1/p" "$frames_dir/truth.txt")"
    read -r -a library <<<"$(sed -n "s/^$frame .*| library \([^|]*\)|.*/\1/p" "$frames_dir/truth.txt")"
    echo 0 >"$tracing/tracing_on"; echo >"$tracing/trace"
    open_at_start="$(hil valve_mask)"
    echo 1 >"$tracing/tracing_on"
    for read_no in 1 2 3; do
      density="$(bus_value ZoneDensity)"
      duty="$(bus_value NozzleDuty)"
      verdict="$(awk -v t="${truth[*]}" -v l="${library[*]}" -v d="$density" -v th="$decision" '
        BEGIN {
          n = split(t, tt, " "); split(l, ll, " "); split(d, dd, " "); bad = (dd[1] != n); e = 0
          for (z = 1; z <= n; z++) {
            x = dd[z + 1] - ll[z]; if (x < 0) x = -x; if (x > e) e = x
            if (tt[z] > 0 && !(dd[z + 1] > th)) bad = 1
            if (tt[z] == 0 && !(dd[z + 1] <= th)) bad = 1
          }
          if (e > 0.01) bad = 1
          printf "%d %.4f\n", bad, e
        }')"
      read -r bad error <<<"$verdict"
      [ "$bad" -eq 0 ] || camera_ok=1
      library_error="$(awk -v a="$library_error" -v b="$error" 'BEGIN { print (b > a) ? b : a }')"
      details+="$frame read $read_no: ZoneDensity ${density#4 } NozzleDuty ${duty#4 }; "
      sleep 0.5
    done
    # Openings per valve line over the reads (writes of 1), and the lines open when they began.
    echo 0 >"$tracing/tracing_on"
    openings="$(awk -v base="$gpio_base" '/ gpio_value: / {
        for (i = 1; i <= NF; i++) if ($i == "gpio_value:") { l = $(i + 1) - base; v = $(i + 3) }
        if (l >= 0 && l < 4 && v == 1) n[l]++ }
      END { for (k = 0; k < 4; k++) printf "%d ", n[k] + 0 }' "$tracing/trace")"
    echo 1 >"$tracing/tracing_on"
    sprayed="$(awk -v t="${truth[*]}" -v o="$openings" -v m="$open_at_start" 'BEGIN {
        n = split(t, tt, " "); split(o, oo, " "); bad = 0
        for (z = 1; z <= n; z++) {
          open = oo[z] > 0 || int(m / 2 ^ (z - 1)) % 2 == 1
          if ((tt[z] > 0) != open) bad = 1
        }
        print bad }')"
    [ "$sprayed" -eq 0 ] || camera_ok=1
    details+="$frame valve openings over the reads ${openings}(open at their start: mask $open_at_start); truth cover ${truth[*]}, library ${library[*]}; "
  done
  hil_command frame field
  figure camera_density_vs_library_max "$library_error"
  info "camera: $(hil camera_writes) frames written, $(hil camera_write_errors) failed; FrameRate $(bus_value FrameRate)"
  step camera_follows_image "$camera_ok" "decision threshold $decision; $details"
fi

# --- tank low -------------------------------------------------------------------------------------
hil_command tank_l 20 # 10 %, below alarms.tank_low_pct = 15
wait_for 10 sh -c 'busctl get-property org.weedspray.Sprayer1 /org/weedspray/Sprayer1 org.weedspray.Sprayer1 Alarms | grep -q tank_low'
step tank_low_raised "$?" "plant tank at $(hil tank_pct) %: TankLevel $(bus_value TankLevel), Alarms $(bus_value Alarms)"
hil_command tank_l 150

# --- a user outside group weedspray ----------------------------------------------------------------
useradd --system --no-create-home --user-group stranger 2>/dev/null || true
sprayctl stop >/dev/null 2>&1
wait_for 10 state_is Idle
state_before="$(bus_state)"
out="$(setpriv --reuid=stranger --regid=stranger --clear-groups sprayctl start 2>&1)"
status=$?
sleep 1
state="$(bus_state)"
step non_member_refused "$([ "$status" -ne 0 ] && [ "$state" = "$state_before" ] && [ "$state" != Spraying ]; echo $?)" \
  "sprayctl start as stranger: status $status ($(echo "$out" | tail -n1 | cut -c1-100)); State $state_before -> $state"

# --- a broken configuration on reload --------------------------------------------------------------
pid_before="$(main_pid)"
refused_before="$(journalctl -u weedsprayd -b -q -o cat | grep -c '^reload refused, running configuration kept' || true)"
echo 'pressure = "not a table"' >/etc/weedspray/conf.d/90-broken.toml
systemctl reload weedsprayd
sleep 3
active="$(systemctl is-active weedsprayd)"
refused_after="$(journalctl -u weedsprayd -b -q -o cat | grep -c '^reload refused, running configuration kept' || true)"
# The daemon must have been asked (ExecReload's SIGHUP) and refused: without the refusal line
# the step would pass for a reload that never reached it.
step broken_reload_keeps_old "$([ "$active" = active ] && [ "$(main_pid)" = "$pid_before" ] && [ "$(bus_value PressureSetpoint)" = "$setpoint" ] && [ "$refused_after" -gt "$refused_before" ]; echo $?)" \
  "after systemctl reload with a broken conf.d file: $active, MainPID $pid_before -> $(main_pid), set-point $(bus_value PressureSetpoint); journal: $(journalctl -u weedsprayd -b -q -o cat | grep -i reload | tail -n1)"
rm -f /etc/weedspray/conf.d/90-broken.toml

# --- faults while spraying: the kernel's record ----------------------------------------------------
# trace_window_begin; fault; trace_analyse SIGNAL PID ->
#   "unsafe_ms exit_ms reopened longest_open_ms wasclosed"
#   unsafe_ms: fatal signal -> every watched line written (a kernel 'set', not a read) since the
#              signal and all of them at 0 (-1: never within the window)
#   exit_ms:   fatal signal -> the main thread's exit (-1: not seen)
#   reopened:  writes of 1 to a watched line after that (until the trace was read), and
#   longest_open_ms the longest any of them held a line open (one still open at the end: the
#              time to the trace's last event, +1000 ms so it cannot pass)
#   wasclosed: 1 when every watched line was already 0 at the signal (a valve between PWM
#              pulses while the cross-watch had the pump off, say)
# The events of the watched lines around the signal (writer thread, ms from the signal, line,
# value) go to $run_dir/fault-events.txt for the step's failure report.
trace_window_begin() { # [PID]: with a PID, that thread's scheduling is traced too
  echo 0 >"$tracing/tracing_on"
  echo >"$tracing/trace"
  if [ -n "${1:-}" ]; then
    echo "prev_pid == $1 || next_pid == $1" >"$tracing/events/sched/sched_switch/filter"
    echo 1 >"$tracing/events/sched/sched_switch/enable"
  else
    echo 0 >"$tracing/events/sched/sched_switch/enable"
  fi
  # What the lines hold when the window opens (the plant's last sample).
  initial_mask="$(hil valve_mask) $(hil pump)"
  echo 1 >"$tracing/tracing_on"
}
trace_analyse() { # SIGNAL PID
  echo 0 >"$tracing/tracing_on"
  awk -v sig="$1" -v pid="$2" -v watched="$watched" -v base="$gpio_base" -v init="$initial_mask" \
    -v events="$run_dir/fault-events.txt" '
    BEGIN {
      n = split(watched, w, " "); for (i = 1; i <= n; i++) watch[w[i]] = 1
      split(init, m, " ")
      for (i = 0; i < 4; i++) latch[base + i] = int(m[1] / 2 ^ i) % 2
      latch[base + 4] = m[2]
      t0 = -1; safe = -1; gone = -1; reopened = 0; longest = 0; wasclosed = 0; last = 0; nb = 0; off = -1; offcpu = 0
      printf "" > events
    }
    function open_lines(   g, c) { c = 0; for (g in watch) if (latch[g] == 1) c++; return c }
    function all_written(   g) { for (g in watch) if (!(g in written)) return 0; return 1 }
    {
      ts = ""; for (i = 1; i <= NF; i++) if ($i ~ /^[0-9]+\.[0-9]+:$/) { ts = substr($i, 1, length($i) - 1) + 0; break }
      if (ts == "") next
      last = ts
    }
    / gpio_value: / {
      for (i = 1; i <= NF; i++) if ($i == "gpio_value:") { g = $(i + 1); how = $(i + 2); v = $(i + 3) }
      if (!(g in watch) || how != "set") next
      if (t0 >= 0 && ts - t0 < 0.5) printf "%s %+.3f ms line %d=%d\n", $1, (ts - t0) * 1000, g - base, v >> events
      if (t0 < 0) { before[nb % 6] = $1 " " ts " line " (g - base) "=" v; nb++ }
      if (safe >= 0 && v == 1 && latch[g] == 0) { reopened++; opened[g] = ts }
      if (safe >= 0 && v == 0 && (g in opened)) {
        if (ts - opened[g] > longest) longest = ts - opened[g]
        delete opened[g]
      }
      latch[g] = v
      if (t0 >= 0) written[g] = 1
      if (t0 >= 0 && safe < 0 && all_written() && open_lines() == 0) safe = ts
      next
    }
    / signal_generate: / && t0 < 0 {
      if ($0 ~ ("sig=" sig " ") && $0 ~ (" pid=" pid " ")) {
        t0 = ts; wasclosed = (open_lines() == 0)
        for (k = (nb > 6 ? nb - 6 : 0); k < nb; k++) {
          split(before[k % 6], e, " ")
          printf "%s %+.3f ms line %s\n", e[1], (e[2] - t0) * 1000, e[4] >> events
        }
        printf "%s +0.000 ms signal %s (lines open: %d)\n", $1, sig, open_lines() >> events
      }
      next
    }
    / sched_process_exit: / && t0 >= 0 && gone < 0 { if ($0 ~ (" pid=" pid " ")) gone = ts }
    # The faulting thread off its CPU between the signal and the safe writes: who ran instead.
    / sched_switch: / && t0 >= 0 && safe < 0 {
      if ($0 ~ (" prev_pid=" pid " ")) {
        off = ts; match($0, /next_comm=[^ ]* next_pid=[0-9]+ next_prio=[0-9]+/); by = substr($0, RSTART, RLENGTH)
        match($0, /prev_state=[^ ]*/); printf "%s %+.3f ms off CPU (%s) for %s\n", $1, (ts - t0) * 1000, substr($0, RSTART, RLENGTH), by >> events
      } else if ($0 ~ (" next_pid=" pid " ") && off >= 0) {
        offcpu += ts - off; off = -1; printf "%s %+.3f ms back on CPU\n", $1, (ts - t0) * 1000 >> events
      }
    }
    END {
      for (g in opened) if (last - opened[g] + 1 > longest) longest = last - opened[g] + 1
      printf "%s %s %d %.3f %d %.3f\n", (t0 >= 0 && safe >= 0) ? sprintf("%.3f", (safe - t0) * 1000) : -1,
        (t0 >= 0 && gone >= 0) ? sprintf("%.3f", (gone - t0) * 1000) : -1, reopened, longest * 1000, wasclosed, offcpu * 1000
    }' "$tracing/trace"
  echo 1 >"$tracing/tracing_on"
}
# A valve written open again after the safe writes must be closed within kReopenLimitMs: a writer
# preempted between the gate and its ioctl (the handler's own CPU on a one-core board, a virtual
# CPU its host descheduled) lands its write late, and closes it again at once
# (EmergencyOutputs::OrdinaryWrite::closed_since_entry). A solenoid needs ~20 ms to open
# (valve_open_delay_s): a pulse under 1 ms moves no liquid; a thread still writing after the
# handler holds it open until the process is gone and the exit watcher writes (tens of ms).
reopen_limit_ms=1
judge_fault() { # NAME SIGNAL PID LIMIT_MS FIGURE_KEY [exit]: prints the figure and the step
  local result unsafe gone reopened longest wasclosed offcpu ok
  result="$(trace_analyse "$2" "$3")"
  read -r unsafe gone reopened longest wasclosed offcpu <<<"$result"
  figure "$5" "$unsafe"
  ok="$(awk -v u="$unsafe" -v g="$gone" -v r="$longest" -v lim="$4" -v rlim="$reopen_limit_ms" -v needexit="${6:-}" \
    'BEGIN { bad = (u < 0 || u > lim || r >= rlim); if (needexit != "" && (g < 0 || u > g)) bad = 1; print bad }')"
  step "$1" "$ok" "signal $2 to PID $3: every valve and the pump written 0 after $unsafe ms (limit $4), main thread gone after $gone ms, lines written open afterwards $reopened (longest open $longest ms, limit $reopen_limit_ms), all closed already at the signal: $wasclosed, the faulting thread off its CPU before the safe writes for $offcpu ms"
  [ "$ok" = 0 ] || info "$1 events of the watched lines: $(tr '\n' '|' <"$run_dir/fault-events.txt" | head -c 3000)"
}

# The E-stop circuit opens while spraying (its line pulled up: an edge the daemon's ws-estop
# thread reads). Figure: from the edge's interrupt in the kernel's record (gpio-sim raises it
# when the pull changes, as a board's GPIO controller does when the contact opens) to every
# valve and the pump written 0. The time from the harness's own trace marker, written just
# before the pull changes, is printed beside it: on the emulated CPU the harness's shell can
# wait for a CPU between the marker and the pull (the daemon's real-time threads run above it),
# which is the stimulus being late, not the stop. Then the stop must hold with the circuit
# closed again until sprayctl clear-alarms.
estop_line=11
estop_pull() { echo "$1" >"$chip_dir/sim_gpio$estop_line/pull"; }
# The E-stop line's interrupt: /proc/interrupts names gpio-sim's interrupt chip (irq_sim), the
# line's offset as its hardware number, and the requester.
estop_irq() {
  awk -v line="$estop_line" '{ for (i = 2; i < NF; i++) if ($i == "irq_sim" && $(i + 1) == line) { sub(":", "", $1); print $1; exit } }' /proc/interrupts
}
marker_to_safe() { # MARKER [IRQ] -> ms from the trace marker (or the first interrupt IRQ after
  # it) to every watched line written 0 (-1: never)
  echo 0 >"$tracing/tracing_on"
  awk -v marker="$1" -v irq="${2:-}" -v watched="$watched" -v base="$gpio_base" -v init="$initial_mask" '
    BEGIN {
      n = split(watched, w, " "); for (i = 1; i <= n; i++) watch[w[i]] = 1
      split(init, m, " ")
      for (i = 0; i < 4; i++) latch[base + i] = int(m[1] / 2 ^ i) % 2
      latch[base + 4] = m[2]
      t0 = -1; safe = -1
    }
    function all_safe(   g) { for (g in watch) if (!(g in written) || latch[g] != 0) return 0; return 1 }
    {
      ts = ""; for (i = 1; i <= NF; i++) if ($i ~ /^[0-9]+\.[0-9]+:$/) { ts = substr($i, 1, length($i) - 1) + 0; break }
      if (ts == "") next
    }
    / tracing_mark_write: / && marked == 0 { if (index($0, marker)) { marked = 1; if (irq == "") t0 = ts }; next }
    / irq_handler_entry: / && marked && t0 < 0 && irq != "" { if (index($0, "irq=" irq " ")) t0 = ts; next }
    / gpio_value: / {
      for (i = 1; i <= NF; i++) if ($i == "gpio_value:") { g = $(i + 1); how = $(i + 2); v = $(i + 3) }
      if (!(g in watch) || how != "set") next
      latch[g] = v
      if (t0 < 0) next
      written[g] = 1
      if (safe < 0 && all_safe()) safe = ts
    }
    END { print (t0 >= 0 && safe >= 0) ? sprintf("%.3f", (safe - t0) * 1000) : -1 }' "$tracing/trace"
  echo 1 >"$tracing/tracing_on"
}
estop_pull pull-down
start_spraying || info "estop: not spraying before it (State=$(bus_state))"
irq="$(estop_irq)"
[ -n "$irq" ] || info "estop: no irq_sim interrupt for line $estop_line in /proc/interrupts: $(grep irq_sim /proc/interrupts | tr -s ' ' | tr '\n' '|')"
echo "irq == ${irq:-0}" >"$tracing/events/irq/irq_handler_entry/filter"
echo 1 >"$tracing/events/irq/irq_handler_entry/enable"
trace_window_begin
echo estop_open >"$tracing/trace_marker"
estop_pull pull-up
wait_for 10 state_is Fault
if [ -n "$irq" ]; then estop_ms="$(marker_to_safe estop_open "$irq")"; else estop_ms=-1; fi
stimulus_ms="$(marker_to_safe estop_open)"
echo 0 >"$tracing/events/irq/irq_handler_entry/enable"
figure estop_safe_ms "$estop_ms"
figure estop_safe_from_marker_ms "$stimulus_ms"
step estop_safe "$(awk -v ms="$estop_ms" 'BEGIN { print (ms >= 0 && ms <= 10) ? 0 : 1 }')" \
  "E-stop line pulled up while spraying: every valve and the pump written 0 after $estop_ms ms from the edge's interrupt (irq ${irq:-none}; limit 10), $stimulus_ms ms from the harness's marker before the pull; the daemon's Estop (closed, latched, edge to safe ms): $(bus_value Estop); State=$(bus_state), Alarms $(bus_value Alarms)"
estop_pull pull-down
sleep 2
step estop_latched "$([ "$(bus_state)" = Fault ] && [ "$(hil pump)" = 0 ]; echo $?)" \
  "circuit closed again, no clear-alarms: State=$(bus_state), pump line $(hil pump), Estop $(bus_value Estop)"
sprayctl clear-alarms >/dev/null 2>&1
wait_for 10 state_is Idle
step estop_reset "$?" "sprayctl clear-alarms with the circuit closed: State=$(bus_state), Estop $(bus_value Estop)"

# The pressure sensor's wire cut while spraying: the plant's loop current drops to 0 mA at the
# ADC input (in_voltage0_raw written 0). The pressure loop reads a sensor fault, never a
# pressure: pump off in that cycle, valves closed. Figure: from weedspray-hil's trace marker
# written just before the ADC input changes to every valve and the pump written 0 (an upper
# bound: it holds the plant's own write). Its marker just after the change is printed beside
# it: on the emulated CPU the daemon's real-time loops can act on the new input before the
# plant writes that one (then -1). The Fault then latches.
# Limit: the issue's 20 ms. The 100 Hz pressure loop reads the ADC once a period, just before
# its deadline, and acts in the cycle that reads the cut: about one period (10 ms) at worst,
# plus the emulated CPU's scheduling.
cut_limit_ms=20
figure sensor_cut_limit_ms "$cut_limit_ms"
start_spraying || info "sensor cut: not spraying before it (State=$(bus_state))"
trace_window_begin
hil_command sensor_wire cut
wait_for 10 state_is Fault
cut_ms="$(marker_to_safe sensor_cut)"
cut_applied_ms="$(marker_to_safe sensor_cut_applied)"
figure sensor_cut_safe_ms "$cut_ms"
figure sensor_cut_safe_from_applied_ms "$cut_applied_ms"
step sensor_cut_safe "$(awk -v ms="$cut_ms" -v lim="$cut_limit_ms" 'BEGIN { print (ms >= 0 && ms <= lim) ? 0 : 1 }')" \
  "pressure sensor wire cut while spraying: every valve and the pump written 0 after $cut_ms ms from the plant's marker before the ADC input changed, $cut_applied_ms ms from its marker after (-1: safe before it) (limit $cut_limit_ms; the pressure loop at 100 Hz); State=$(bus_state), Alarms $(bus_value Alarms), pump line $(hil pump), valve lines $(hil valve_mask), plant pressure $(hil pressure_mpa) MPa"
hil_command sensor_wire mended
sleep 1
sprayctl clear-alarms >/dev/null 2>&1
wait_for 10 state_is Idle
step sensor_mended "$?" "wire mended, sprayctl clear-alarms: State=$(bus_state), Alarms $(bus_value Alarms), Pressure $(bus_value Pressure) MPa"

# kill -9: nothing runs in the daemon; ExecStopPost must write the lines safe.
# (Each fault costs a restart, the slowest part on an emulated CPU: the orderly stop comes last.)
# The exit watcher killed: the daemon starts another and hands it the outputs (the kill -9
# below then measures the new one).
watcher_pid() { pgrep -f -- "--when-closed 3 --daemon-pid $(main_pid)" | head -n1; }
old_watcher="$(watcher_pid)"
journal_lines="$(journalctl -u weedsprayd -b -o cat | wc -l)"
[ -n "$old_watcher" ] && kill -9 "$old_watcher"
new_watcher_started() { local w; w="$(watcher_pid)"; [ -n "$w" ] && [ "$w" != "$old_watcher" ] && journalctl -u weedsprayd -b -o cat | tail -n +$((journal_lines + 1)) | grep -q "exit watcher (pid $w) holds the safe writes"; }
wait_for 10 new_watcher_started
step watcher_restarted "$?" "exit watcher pid ${old_watcher:-none} killed: now pid $(watcher_pid); journal: $(journalctl -u weedsprayd -b -o cat | tail -n +$((journal_lines + 1)) | grep -i "watcher" | tr '\n' '|'); State=$(bus_state)"

# The configuration is broken (a typo being edited) when the daemon dies: the safe writers read
# the output manifest the daemon wrote at its start under /run, not the files. The typo goes
# once ExecStopPost has spoken, before RestartSec (2 s) ends, so the restart below still runs.
start_spraying || info "kill -9: not spraying before the fault (State=$(bus_state))"
pid="$(main_pid)"
manifest_valves="$(grep -c "^valve_names = \[ .valve0., .valve1., .valve2., .valve3. \]" /run/weedspray/outputs.toml)"
printf '[gpio]\nvalve_ofsets = [0]\n' >/etc/weedspray/conf.d/90-typo.toml
journal_lines="$(journalctl -u weedsprayd -b -o cat | wc -l)"
stop_post_said() { journalctl -u weedsprayd -b -o cat | tail -n +$((journal_lines + 1)) | grep -q "^weedspray-safe-outputs: \(outputs written safe\|/etc/weedspray\)"; }
trace_window_begin
started="$(now)"
kill -9 "$pid"
wait_for 30 stop_post_said
stop_post="$(journalctl -u weedsprayd -b -o cat | tail -n +$((journal_lines + 1)) | grep "^weedspray-safe-outputs: " | grep -v "weedsprayd e[xn]" | tr '\n' '|')"
rm -f /etc/weedspray/conf.d/90-typo.toml
step kill9_config_broken "$([ "$manifest_valves" = 1 ] && grep -q "^weedspray-safe-outputs: outputs written safe|$" <<<"$stop_post"; echo $?)" \
  "gpio.valve_ofsets typo in conf.d, then kill -9: ExecStopPost said '$stop_post' (manifest /run/weedspray/outputs.toml names the 4 valves: $manifest_valves)"
wait_for 120 active_with_new_pid "$pid"
restart_s="$(elapsed "$started")"
wait_for 15 state_is Idle
sleep 1 # after the restart too: nothing written open while Idle
judge_fault kill9_safe 9 "$pid" 100 kill9_unsafe_ms
figure restart_s "$restart_s"
step restart "$([ "$(systemctl is-active weedsprayd)" = active ]; echo $?)" "kill -9 -> active again (new MainPID $(main_pid)) in $restart_s s (RestartSec=2s + start-up), State=$(bus_state)"

# Crashes inside the daemon: the fatal-signal handlers write the lines safe before it is gone.
crash() { # NAME SIGNAL_TO_SEND EXPECTED_FATAL_SIGNAL LIMIT_MS FIGURE_KEY
  start_spraying || info "$1: not spraying before the fault (State=$(bus_state))"
  local pid
  pid="$(main_pid)"
  trace_window_begin "$pid"
  kill -s "$2" "$pid"
  wait_for 120 active_with_new_pid "$pid"
  wait_for 15 state_is Idle
  sleep 1
  judge_fault "$1" "$3" "$pid" "$4" "$5" exit
}
crash abort_safe RTMIN+1 6 10 abort_unsafe_ms
crash segv_safe RTMIN+2 11 10 segv_unsafe_ms
# A hung main loop: no WATCHDOG=1 for WatchdogSec (2 s), systemd sends SIGABRT.
crash watchdog_safe RTMIN+3 6 100 watchdog_unsafe_ms
info "journal of the faults: $(journalctl -u weedsprayd -b -q -o cat | grep -E 'watchdog|dumped core|Main process exited|outputs written safe|test crash hook' | sort | uniq -c | tr '\n' '|')"

# The system bus dies while spraying (dbus-daemon killed): nobody can stop the sprayer over
# D-Bus any more, so the daemon stops by itself (valves closed, pump off) and exits for systemd
# to restart it, Idle, once the bus is back. Figure: from a trace marker written just before
# the kill to every valve and the pump written 0; limit 1000 ms, as for an orderly stop.
start_spraying || info "bus lost: not spraying before it (State=$(bus_state))"
pid="$(main_pid)"
bus_pid="$(systemctl show -p MainPID --value dbus)"
daemon_gone() { ! kill -0 "$pid" 2>/dev/null; }
trace_window_begin
echo bus_killed >"$tracing/trace_marker"
kill -9 "$bus_pid"
wait_for 30 daemon_gone
bus_ms="$(marker_to_safe bus_killed)"
figure bus_lost_safe_ms "$bus_ms"
bus_exit="$(journalctl -u weedsprayd -b -o cat | grep -c "D-Bus connection lost")"
systemctl start dbus.socket dbus.service
wait_for 120 active_with_new_pid "$pid"
wait_for 15 state_is Idle
step bus_lost_safe "$(awk -v ms="$bus_ms" -v said="$bus_exit" -v st="$(bus_state)" 'BEGIN { print (ms >= 0 && ms <= 1000 && said > 0 && st == "Idle") ? 0 : 1 }')" \
  "dbus-daemon (PID $bus_pid) killed while spraying: every valve and the pump written 0 after $bus_ms ms (limit 1000), 'D-Bus connection lost' in the journal $bus_exit time(s); restarted as PID $(main_pid), State=$(bus_state), Alarms $(bus_value Alarms)"

# systemctl stop while spraying.
start_spraying || info "stop: not spraying before it (State=$(bus_state))"
trace_window_begin
pid="$(main_pid)"
timeout 30 systemctl stop weedsprayd
result="$(systemctl show -p Result --value weedsprayd)"
read -r unsafe _ reopened _ wasclosed <<<"$(trace_analyse 15 "$pid")" # SIGTERM
sleep 0.5
dac="$(hil dac_volts)"
# An orderly stop joins the valve thread before its last safe writes: nothing may write open after.
step stop_safe "$(awk -v u="$unsafe" -v r="$result" -v d="$dac" -v o="$reopened" 'BEGIN { print (r == "success" && u >= 0 && u <= 1000 && o == 0 && d >= 3.29) ? 0 : 1 }')" \
  "systemctl stop while spraying (all closed already: $wasclosed): Result=$result, valves and pump written 0 $unsafe ms after SIGTERM, lines written open afterwards $reopened, return-valve DAC $dac V (3.3 = fully open), pressure $(hil pressure_mpa) MPa"


# --- the plant's own ground truth ---------------------------------------------------------------
echo quit >"$run_dir/control"
wait "$hil_pid"
hil_pid=""
grep -a '^WEEDSPRAY-HIL-TRUTH' "$hil_log"
echo "    ---- journalctl -u weedsprayd (HIL part, last 80 lines) ----"
journalctl -u weedsprayd -b --no-pager -o short-monotonic | tail -n 80 | sed 's/^/    /'
finish
