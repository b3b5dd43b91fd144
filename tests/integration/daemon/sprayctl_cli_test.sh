#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# sprayctl's command line and exit statuses (sprayctl(1) EXIT STATUS): --version names the
# project's version; a bare call and usage errors print usage and exit 2, without a bus; with
# no session bus, and on a PRIVATE session bus without weedsprayd, it says weedsprayd is not
# running and exits 3; against weedsprayd --sim a request done exits 0 and one the daemon
# refuses exits 1 with the daemon's reason; set-rate and set-threshold show in the status.
# usage: sprayctl_cli_test.sh BUILD_DIR VERSION
set -euo pipefail
BUILD=$(realpath "$1")
VERSION=$2
WEEDSPRAYD=$BUILD/daemon/weedsprayd
SPRAYCTL=$BUILD/daemon/sprayctl
. "$(dirname "$0")/private_bus_lib.sh" sprayctl-cli

# expect STATUS PATTERN ARGS...: sprayctl ARGS (run under `env ${ENV[@]}`) exits STATUS and its
# output (both streams) matches the extended regular expression PATTERN.
ENV=()
expect() {
  local want=$1 pattern=$2 got=0
  shift 2
  env "${ENV[@]}" "$SPRAYCTL" "$@" >"$T/out.txt" 2>&1 || got=$?
  [ "$got" -eq "$want" ] || fail "sprayctl $*: exit status $got, expected $want: $(cat "$T/out.txt")"
  grep -qE -- "$pattern" "$T/out.txt" || fail "sprayctl $*: '$pattern' not in: $(cat "$T/out.txt")"
}

expect 0 "^sprayctl ${VERSION//./\\.}$" --version
expect 2 "^Usage: sprayctl " # bare
expect 2 "required|not expected|could not be matched" no-such-command
expect 2 "MPA is required" set-pressure
expect 2 "could not be converted|Could not convert" set-pressure high
expect 2 "--seconds S .* or --volume L" calibrate meter
# Nobody to talk to: no session bus in this shell (no address, then an address with no bus
# behind it), then a bus without the daemon.
ENV=(-u DBUS_SESSION_BUS_ADDRESS -u XDG_RUNTIME_DIR)
expect 3 "^sprayctl: weedsprayd is not reachable: this shell has no session bus" --user status
ENV=(-u DBUS_SESSION_BUS_ADDRESS XDG_RUNTIME_DIR="$T")
expect 3 "^sprayctl: weedsprayd is not running \(cannot connect to the session bus" --user status
ENV=()
start_private_bus
expect 3 "^sprayctl: weedsprayd is not running \(no org\.weedspray\.Sprayer1 on the session bus\)$" \
  --user status
expect 3 "weedsprayd is not running" --user start

cat >"$T/weedspray.toml" <<'TOML'
[sim]
speed_profile = "constant"
speed_max_m_per_s = 1.0
[spray]
target_rate_l_per_ha = 150.0
TOML
start_sim_daemon --run-seconds 60
expect 0 "^State: *Idle" --user status
# Outside the set-point's range: refused by the daemon, which says why.
expect 1 "^sprayctl: org\.weedspray\.Sprayer1\.Error\.[A-Za-z]+: .*" --user set-pressure 5.0
echo "ok: sprayctl --version, usage (2), not running (3), done (0) and refused (1)"

# Typed JSON: numbers in the units named under "units", structures as objects, a timestamp.
"$SPRAYCTL" --user status --json >"$T/status.json" || fail "status --json"
python3 - "$T/status.json" <<'PY' || fail "status --json: $(cat "$T/status.json")"
import datetime, json, sys
j = json.load(open(sys.argv[1]))
assert isinstance(j["Pressure"], float) and j["units"]["Pressure"] == "MPa", j
assert j["units"]["Flow"] == "L/min" and j["units"]["NozzleDuty"] == "%", j["units"]
assert isinstance(j["Estop"]["circuit_closed"], bool) and "last_reaction_ms" in j["Estop"], j["Estop"]
assert set(j["MeterCalibration"]) >= {"source", "pulses_per_litre"}, j["MeterCalibration"]
assert set(j["Calibration"]) == {"state", "progress", "message"}, j["Calibration"]
age = datetime.datetime.now(datetime.timezone.utc) - datetime.datetime.fromisoformat(j["timestamp"].replace("Z", "+00:00"))
assert abs(age.total_seconds()) < 5, (j["timestamp"], age)
PY
expect 0 '^\{"Alarms":\[.*\],"timestamp":"[0-9T:.-]+Z"\}$' --user alarms --json
echo "ok: status --json typed, with units and a timestamp"

# Commissioning in Idle: the raw inputs, one valve alone against the meter, the pump alone.
expect 0 "^pressure_sensor_current +[0-9.]+  mA$" --user inputs
grep -qE "^flow_pulses +[0-9]+  pulses$" "$T/out.txt" || fail "inputs: no flow meter: $(cat "$T/out.txt")"
expect 0 '^\{"RawInputs":\{.*"flow_pulses":\{"unit":"pulses","value":[0-9.e+]+\}' --user inputs --json
expect 0 "valve test: nozzle 1 at 100 % for 2 s: [0-9]+ pulses, [0-9.]+ L, 0\.[0-9]+ L/min by the meter" \
  --user test valve 1 --seconds 2
expect 0 "pump test: 0\.[0-9]+ MPa reached after [0-9.]+ s" --user test pump --seconds 4
expect 1 "TestValve refused: nozzle 9 does not exist" --user test valve 9
expect 1 "a valve test lasts 1\.\.60 s" --user test valve 0 --seconds 90
expect 0 "dose at full weed cover 150\.0 L/ha" --user status
echo "ok: sprayctl inputs, test valve, test pump"

# The dose and the decision threshold set live: the status shows them at once; a dose no nozzle
# can give and a threshold outside 0..1 are refused with the figures.
"$SPRAYCTL" --user set-rate 180 || fail "set-rate 180"
"$SPRAYCTL" --user set-threshold 0.3 || fail "set-threshold 0.3"
"$SPRAYCTL" --user --json status >"$T/status.json" || fail "status --json"
python3 - "$T/status.json" <<'PY' || fail "after set-rate/set-threshold: $(cat "$T/status.json")"
import json, sys
j = json.load(open(sys.argv[1]))
assert abs(j["TargetRate"] - 180.0) < 1e-6 and j["units"]["TargetRate"] == "L/ha", j["TargetRate"]
assert abs(j["DecisionThreshold"] - 0.3) < 1e-12, j["DecisionThreshold"]
PY
expect 1 "InvalidArgument: 10000 L/ha .* needs 30 L/min per nozzle, outside the nozzles' 0\.01\.\.20 L/min" \
  --user set-rate 10000
expect 1 "InvalidArgument: decision threshold 1\.5 outside spray\.decision_threshold's range 0\.\.1" \
  --user set-threshold 1.5
expect 2 "L_PER_HA is required" set-rate
expect 0 "dose at full weed cover 180\.0 L/ha" --user status
grep -q "(sprayed from 0\.300)" "$T/out.txt" || fail "status: no threshold: $(cat "$T/out.txt")"
# As the pressure set-point, they last until the configuration is reloaded.
"$SPRAYCTL" --user reload || fail "reload"
expect 0 "dose at full weed cover 150\.0 L/ha" --user status
grep -q "(sprayed from 0\.001)" "$T/out.txt" || fail "reload kept the threshold: $(cat "$T/out.txt")"
echo "ok: sprayctl set-rate, set-threshold"

# The live view: two frames a fifth of a second apart, each with every nozzle's bar.
"$SPRAYCTL" --user start || fail "start"
expect 1 "TestPump refused: tests run in Idle" --user test pump
expect 0 "^Rate: +[0-9]+\.[0-9] L/ha now over the boom" --user status
expect 0 "Applied .* L/ha over the job" --user top --frames 2 --interval 0.2
[ "$(grep -c '^weedsprayd  Spraying' "$T/out.txt")" -eq 2 ] || fail "top: not 2 frames: $(cat "$T/out.txt")"
[ "$(grep -cE '^ +[0-9]+    \[[# ]{30}\] +[0-9]+ %' "$T/out.txt")" -eq 8 ] ||
  fail "top: not 4 nozzle bars (the default boom) a frame: $(cat "$T/out.txt")"
expect 2 "interval" --user top --interval 0
echo "ok: sprayctl top"
