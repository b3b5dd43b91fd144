#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# weedsprayd --sim runs the machine [sim] names (without a bus, so spraying at once; 3 nozzles at
# a constant 1 m/s):
#  1. machine = "ideal": the ideal bench, and the daemon says so;
#  2. machine = "drawn", machine_seed = 3: the daemon logs the drawn machine, whose nozzles' true
#     flow coefficients and meter error are not the ideal bench's, and it sprays on it;
#  3. the same seed again is the same machine; machine_seed = 4 another.
# usage: drawn_machine_sim_test.sh BUILD_DIR
set -euo pipefail
BUILD=$(realpath "$1")
. "$(dirname "$0")/private_bus_lib.sh" drawn-machine
FAIL_LOGS=()

run() {  # run NAME SECONDS [TOML LINE...]: weedsprayd --sim on those [sim] lines
  local name=$1 seconds=$2
  shift 2
  printf '%s\n' "[daemon]" "autostart = true" "[boom]" "nozzles = 3" "[sim]" \
    'speed_profile = "constant"' "speed_max_m_per_s = 1.0" "$@" >"$T/$name.toml"
  FAIL_LOGS+=("$T/$name.log")
  HOME="$T" "$BUILD/daemon/weedsprayd" --sim --no-bus --config "$T/$name.toml" \
    --state-dir "$T/state-$name" --run-seconds "$seconds" --sim-truth-file "$T/$name.truth" \
    >"$T/$name.log" 2>&1 || fail "$name: weedsprayd exit status $?"
}
machine() {  # machine NAME: the machine the run logged at start
  sed -n 's/.*sim: \(.*(plant seed .*\)$/\1/p' "$T/$1.log" | head -n 1
}
nozzles() {  # nozzles NAME: its nozzles' true flow coefficients
  machine "$1" | sed -n 's/.*nozzle k [^)]*) \([^;]*\);.*/\1/p'
}
truth() {  # truth NAME KEY: a value of the plant's truth at exit
  sed -n "s/^$2=//p" "$T/$1.truth"
}

run ideal 4 'machine = "ideal"'
machine ideal | grep -q "^ideal bench (plant seed 1)" || fail "ideal: logged '$(machine ideal)'"

run drawn3 4 'machine = "drawn"' "machine_seed = 3"
machine drawn3 | grep -q "^drawn machine 0 of fleet 3 (plant seed [0-9]*)" ||
  fail "drawn3: logged '$(machine drawn3)'"
[ -n "$(nozzles drawn3)" ] || fail "drawn3: no nozzle coefficients in '$(machine drawn3)'"
[ "$(nozzles drawn3)" != "$(nozzles ideal)" ] ||
  fail "the drawn machine's nozzles are the ideal bench's: $(nozzles drawn3)"
[ "$(truth drawn3 meter_gain)" != "$(truth ideal meter_gain)" ] ||
  fail "the drawn machine's meter is the ideal bench's: gain $(truth drawn3 meter_gain)"
/usr/bin/python3 -c "import sys; sys.exit(0 if float(sys.argv[1]) > 0.005 else 1)" \
  "$(truth drawn3 sprayed_l)" || fail "drawn3: sprayed $(truth drawn3 sprayed_l) L"
echo "ok: ideal bench: nozzle k $(nozzles ideal), meter gain $(truth ideal meter_gain)"
echo "ok: drawn machine 3: nozzle k $(nozzles drawn3), meter gain $(truth drawn3 meter_gain)," \
  "sprayed $(truth drawn3 sprayed_l) L"

run again3 1 'machine = "drawn"' "machine_seed = 3"
[ "$(machine again3)" = "$(machine drawn3)" ] ||
  fail "seed 3 twice: '$(machine drawn3)' then '$(machine again3)'"
run drawn4 1 "machine_seed = 4"  # drawn is the default
machine drawn4 | grep -q "^drawn machine 0 of fleet 4" || fail "drawn4: logged '$(machine drawn4)'"
[ "$(nozzles drawn4)" != "$(nozzles drawn3)" ] || fail "seeds 3 and 4: the same nozzles"
echo "ok: seed 3 again the same machine; seed 4 (the default machine kind) another"
