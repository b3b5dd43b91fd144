#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# weedsprayd --check-config refuses trip limits that would let a fault pass (a cut sensor wire
# read as a pressure, an over-pressure trip beyond the sensor's full scale), naming
# file:line: key, as the daemon does at start, and a hardware configuration without a heartbeat
# output or without an emergency-stop input unless its opt-out is set; the shipped
# configuration passes once each has a line or its opt-out.
# usage: check_config_test.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
BUILD=$(realpath "$1")
SOURCE=$(realpath "$2")
T=$(mktemp -d /tmp/weedspray-check-config.XXXXXX)
trap 'rm -rf "$T"' EXIT
fail() {
  echo "FAIL: $*" >&2
  cat "$T"/*.log >&2 2>/dev/null || true
  exit 1
}
refused() {  # refused NAME LOCATION: NAME.toml refused with LOCATION in the message
  local name=$1 location=$2
  if "$BUILD/daemon/weedsprayd" --check-config --config "$T/$name.toml" >"$T/$name.log" 2>&1; then
    fail "$name: accepted"
  fi
  grep -q "^weedsprayd: $T/$name.toml:$location" "$T/$name.log" || fail "$name: not located"
  echo "ok: $name refused: $(cat "$T/$name.log")"
}

# The shipped configuration wires no heartbeat: hardware mode refuses it, at the key, until a
# heartbeat line or the opt-out is set (a drop-in); a simulation needs none.
mkdir -p "$T/etc/conf.d"
cp "$SOURCE/etc/weedspray.toml" "$T/etc/weedspray.toml"
line=$(grep -n '^heartbeat_offset = -1$' "$T/etc/weedspray.toml" | cut -d: -f1)
[ -n "$line" ] || fail "the shipped configuration sets no heartbeat_offset"
cp "$T/etc/weedspray.toml" "$T/shipped.toml"
refused shipped "$line: gpio.heartbeat_offset: hardware mode needs a heartbeat output"
if "$BUILD/daemon/weedsprayd" --no-bus --run-seconds 1 --config "$T/etc/weedspray.toml" \
  >"$T/start.log" 2>&1; then
  fail "weedsprayd started in hardware mode without a heartbeat"
fi
grep -q "^weedsprayd: $T/etc/weedspray.toml:$line: gpio.heartbeat_offset: hardware mode needs" \
  "$T/start.log" || fail "start without a heartbeat: $(cat "$T/start.log")"
echo "ok: start without a heartbeat refused: $(cat "$T/start.log")"
"$BUILD/daemon/weedsprayd" --sim --check-config --config "$T/etc/weedspray.toml" >"$T/sim.log" 2>&1 ||
  fail "the shipped configuration is refused for a simulation"
printf '[gpio]\nheartbeat_opt_out = true\nestop_opt_out = true\n' >"$T/etc/conf.d/50-opt-out.toml"
"$BUILD/daemon/weedsprayd" --check-config --config "$T/etc/weedspray.toml" >"$T/opt-out.log" 2>&1 ||
  fail "the opt-outs are refused"
grep -q "^weedsprayd: warning: gpio.heartbeat_opt_out = true: no heartbeat output" "$T/opt-out.log" ||
  fail "the heartbeat opt-out is not warned about"
grep -q "^weedsprayd: warning: gpio.estop_opt_out = true: no emergency-stop input" "$T/opt-out.log" ||
  fail "the E-stop opt-out is not warned about"
# With a heartbeat, the missing emergency-stop input is refused at its key.
printf '[gpio]\nheartbeat_name = "HEARTBEAT"\n' >"$T/etc/conf.d/50-opt-out.toml"
estop_line=$(grep -n '^estop_offset = -1$' "$T/etc/weedspray.toml" | cut -d: -f1)
[ -n "$estop_line" ] || fail "the shipped configuration sets no estop_offset"
if "$BUILD/daemon/weedsprayd" --check-config --config "$T/etc/weedspray.toml" >"$T/no_estop.log" 2>&1; then
  fail "accepted without an emergency-stop input"
fi
grep -q "^weedsprayd: $T/etc/weedspray.toml:$estop_line: gpio.estop_offset: hardware mode needs an emergency-stop input" \
  "$T/no_estop.log" || fail "no E-stop: not refused at its key: $(cat "$T/no_estop.log")"
echo "ok: no E-stop refused: $(cat "$T/no_estop.log")"
printf '[gpio]\nheartbeat_name = "HEARTBEAT"\nestop_name = "ESTOP"\n' >"$T/etc/conf.d/50-opt-out.toml"
"$BUILD/daemon/weedsprayd" --check-config --config "$T/etc/weedspray.toml" >"$T/heartbeat.log" 2>&1 ||
  fail "the shipped configuration with a heartbeat and an E-stop is refused"
if grep -q "warning" "$T/heartbeat.log"; then fail "warned with both lines: $(cat "$T/heartbeat.log")"; fi
rm -f "$T"/etc/conf.d/*.toml

printf '[alarms]\nsensor_fault_low_ma = 0\n' >"$T/cut_wire.toml"
refused cut_wire "2: alarms.sensor_fault_low_ma: 0 is outside"
printf '[alarms]\nsensor_fault_low_ma = 1.0\n' >"$T/leaky_wire.toml"
refused leaky_wire "2: alarms.sensor_fault_low_ma: 1 is outside"
printf '[alarms]\nsensor_fault_high_ma = 30\n' >"$T/short.toml"
refused short "2: alarms.sensor_fault_high_ma: 30 is outside"
printf '[pressure]\nsensor_max_mpa = 1.0\n[alarms]\nover_pressure_mpa = 1.2\n' >"$T/trip.toml"
refused trip "4: alarms.over_pressure_mpa: .* must be below pressure.sensor_max_mpa"

# What the daemon would refuse at start is refused here: more cameras than a board runs, minimum
# valve times that do not fit a PWM period (every numeric key at its range's ends is checked
# against the daemon's own construction by ConfigBounds.* in daemon_sim_tests).
for i in $(seq 0 8); do printf '[[camera]]\nfirst_nozzle = %d\nnozzle_count = 1\n' "$i"; done \
  >"$T/cameras.toml"
sed -i '1i [boom]\nnozzles = 9' "$T/cameras.toml"
refused cameras "27: camera\\[8\\]: 9 \\[\\[camera\\]\\] tables: at most 8 cameras"
printf '[pwm]\nfrequency_hz = 20\nmin_on_s = 0.04\nmin_off_s = 0.02\n' >"$T/pwm.toml"
refused pwm "3: pwm.min_on_s: pwm.min_on_s + pwm.min_off_s (0.06 s) must fit"
# A file far larger than any configuration (a log saved under its name) is refused at once,
# before it is parsed: a reload of it would stall the daemon's main loop for seconds.
{
  printf '[gpio]\n'
  head -c 2000000 /dev/zero | tr '\0' '#'
  printf '\n'
} >"$T/huge.toml"
start=$(date +%s%N)
refused huge " 2000008 bytes: a configuration file has at most 1048576 bytes"
[ $((($(date +%s%N) - start) / 1000000)) -lt 1000 ] || fail "the huge file took over a second"
echo PASS
