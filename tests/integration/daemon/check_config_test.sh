#!/usr/bin/env bash
# weedsprayd --check-config refuses trip limits that would let a fault pass (a cut sensor wire
# read as a pressure, an over-pressure trip beyond the sensor's full scale), naming
# file:line: key, as the daemon does at start; the shipped configuration passes.
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

"$BUILD/daemon/weedsprayd" --check-config --config "$SOURCE/etc/weedspray.toml" >"$T/shipped.log" 2>&1 ||
  fail "the shipped configuration is refused"

printf '[alarms]\nsensor_fault_low_ma = 0\n' >"$T/cut_wire.toml"
refused cut_wire "2: alarms.sensor_fault_low_ma: 0 is outside"
printf '[alarms]\nsensor_fault_low_ma = 1.0\n' >"$T/leaky_wire.toml"
refused leaky_wire "2: alarms.sensor_fault_low_ma: 1 is outside"
printf '[alarms]\nsensor_fault_high_ma = 30\n' >"$T/short.toml"
refused short "2: alarms.sensor_fault_high_ma: 30 is outside"
printf '[pressure]\nsensor_max_mpa = 1.0\n[alarms]\nover_pressure_mpa = 1.2\n' >"$T/trip.toml"
refused trip "4: alarms.over_pressure_mpa: .* must be below pressure.sensor_max_mpa"
echo PASS
