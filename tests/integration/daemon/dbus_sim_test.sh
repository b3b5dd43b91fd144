#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# weedsprayd --sim on a PRIVATE session bus, driven with busctl and sprayctl:
# properties, Start -> pressure at set-point and duties following densities, a refused bad
# set-point, a refused broken reload (old config keeps running), a reloaded trip limit kept until
# a restart, SIGTERM -> valves closed, exit 0.
# usage: dbus_sim_test.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
BUILD=$(realpath "$1")
SOURCE=$(realpath "$2")
WEEDSPRAYD=$BUILD/daemon/weedsprayd
SPRAYCTL=$BUILD/daemon/sprayctl
PY=/usr/bin/python3
. "$(dirname "$0")/private_bus_lib.sh" dbus
start_private_bus

prop() {  # prop NAME -> value as busctl prints it, without the type letter
  busctl --user get-property org.weedspray.Sprayer1 /org/weedspray/Sprayer1 \
    org.weedspray.Sprayer1 "$1" | cut -d' ' -f2-
}
status_json() { "$SPRAYCTL" --user status --json; }
json_get() {  # json_get EXPR (python, j = the status object)
  status_json | $PY -c "import json,sys; j=json.load(sys.stdin); print($1)"
}

mkdir -p "$T/etc/conf.d" "$T/state"
cp "$SOURCE/etc/weedspray.toml" "$T/etc/weedspray.toml"
cat >"$T/etc/conf.d/10-test.toml" <<'TOML'
[spray]
max_density = 0.05          # the field images are sparse: make their weeds worth spraying
decision_threshold = 0.005
[sim]
speed_profile = "constant"
speed_max_m_per_s = 1.0
TOML

"$WEEDSPRAYD" --sim --user --config "$T/etc/weedspray.toml" --state-dir "$T/state" \
  --valve-state-file "$T/valves.txt" >"$T/daemon.log" 2>&1 &
DAEMON_PID=$!

# Up and Idle within 20 s.
for _ in $(seq 1 100); do
  state=$(prop State 2>/dev/null || true)
  [ "$state" = '"Idle"' ] && break
  kill -0 "$DAEMON_PID" 2>/dev/null || fail "weedsprayd exited during start-up"
  sleep 0.2
done
[ "$state" = '"Idle"' ] || fail "State is '$state', expected Idle"
echo "ok: Idle on the bus"

# Every property is there and sane.
busctl --user introspect org.weedspray.Sprayer1 /org/weedspray/Sprayer1 org.weedspray.Sprayer1 \
  >"$T/introspect.txt"
for p in State Pressure PressureSetpoint Flow TankLevel Speed Distance NozzleDuty ZoneDensity \
  Alarms VolumeSprayed AreaCovered SavingsPercent FrameRate VisionLatencyMs ControlOverruns; do
  grep -q "^\.$p " "$T/introspect.txt" || fail "property $p missing"
done
for m in Start Stop SetPressureSetpoint ReloadConfig ClearAlarms AlarmRaised AlarmCleared; do
  grep -q "^\.$m " "$T/introspect.txt" || fail "member $m missing"
done
[ "$(prop PressureSetpoint)" = "0.4" ] || fail "PressureSetpoint $(prop PressureSetpoint)"
[ "$(prop NozzleDuty)" = "4 0 0 0 0" ] || fail "NozzleDuty in Idle: $(prop NozzleDuty)"
# The wheel-speed estimate needs a few pulses after start-up: give it up to 5 s to settle.
speed_ok=0
for _ in $(seq 1 20); do
  if $PY - "$(prop TankLevel)" "$(prop Speed)" <<'PYEOF'; then speed_ok=1; break; fi
import sys
tank, speed = float(sys.argv[1]), float(sys.argv[2])
assert 0 < tank <= 100, tank
assert 0.9 < speed < 1.1, speed
PYEOF
  sleep 0.25
done
[ "$speed_ok" = 1 ] || fail "TankLevel/Speed out of range: $(prop TankLevel) $(prop Speed)"
# Idle: pump off, so the line holds no pressure.
$PY - "$(prop Pressure)" <<'PYEOF' || fail "pressure in Idle: $(prop Pressure) MPa (pump should be off)"
import sys
assert float(sys.argv[1]) < 0.05, sys.argv[1]
PYEOF
echo "ok: properties present"

"$SPRAYCTL" --user start || fail "Start refused"
[ "$(prop State)" = '"Spraying"' ] || fail "not Spraying after Start"
if "$SPRAYCTL" --user start 2>"$T/err.txt"; then fail "second Start accepted"; fi
grep -q "NotPermitted" "$T/err.txt" || fail "second Start: $(cat "$T/err.txt")"

# Duties follow the pinned densities: sample for 8 s.
: >"$T/samples.jsonl"
for _ in $(seq 1 32); do status_json >>"$T/samples.jsonl"; sleep 0.25; done
$PY - "$T/samples.jsonl" <<'PYEOF' || fail "duties do not follow densities"
import json, sys
samples = [json.loads(line) for line in open(sys.argv[1])]
sprayed = 0
for s in samples:
    assert s["State"] == "Spraying", s["State"]
    for duty, density in zip(s["NozzleDuty"], s["ZoneDensity"]):
        if density < 0.005:
            assert duty == 0, f"density {density} below the decision threshold but duty {duty}"
        if duty > 0:
            sprayed += 1
            assert duty >= 20, f"duty {duty} inside the closed band"
assert sprayed > 0, "no nozzle ever opened"
pressures = [s["Pressure"] for s in samples[8:]]
assert all(abs(p - 0.4) < 0.05 for p in pressures), f"pressure off set-point: {pressures}"
print(f"ok: {sprayed} open nozzle samples; pressure {min(pressures):.3f}..{max(pressures):.3f} MPa")
PYEOF

# A bad set-point is refused with a reason; a good one is followed.
if "$SPRAYCTL" --user set-pressure 5.0 2>"$T/err.txt"; then fail "set-pressure 5.0 accepted"; fi
grep -q "org.weedspray.Sprayer1.Error.InvalidArgument" "$T/err.txt" || fail "$(cat "$T/err.txt")"
grep -q "pressure 5 MPa outside 0.05" "$T/err.txt" || fail "$(cat "$T/err.txt")"
busctl --user call org.weedspray.Sprayer1 /org/weedspray/Sprayer1 org.weedspray.Sprayer1 \
  SetPressureSetpoint d 0.3
sleep 3
$PY -c "import sys; p=float(sys.argv[1]); assert abs(p-0.3) < 0.03, p" "$(prop Pressure)" ||
  fail "pressure $(prop Pressure) not at the new set-point 0.3"
echo "ok: set-point validation and tracking"

# A broken drop-in: reload refused (over D-Bus and on SIGHUP), the running config stays.
printf '[pressure]\nsetpoint_mpa = 7\n' >"$T/etc/conf.d/99-broken.toml"
if "$SPRAYCTL" --user reload 2>"$T/err.txt"; then fail "broken reload accepted"; fi
grep -q "99-broken.toml:2: pressure.setpoint_mpa: 7 is outside" "$T/err.txt" ||
  fail "reload error: $(cat "$T/err.txt")"
kill -HUP "$DAEMON_PID"
sleep 0.5
kill -0 "$DAEMON_PID" || fail "SIGHUP with a broken file killed the daemon"
[ "$(prop State)" = '"Spraying"' ] || fail "state changed by a refused reload"
[ "$(prop PressureSetpoint)" = "0.3" ] || fail "set-point changed by a refused reload"
grep -q "reload refused" "$T/daemon.log" || fail "refused reload not logged"
printf '[pressure]\nsetpoint_mpa = 0.25\n' >"$T/etc/conf.d/99-broken.toml"
"$SPRAYCTL" --user reload || fail "valid reload refused"
[ "$(prop PressureSetpoint)" = "0.25" ] || fail "valid reload not applied"
echo "ok: reload"

# A reload that raises the over-pressure trip: the live set-point applies, the trip keeps its
# running value until a restart (logged), so the set-point stays bounded by the old trip.
printf '[pressure]\nsetpoint_mpa = 0.26\n[alarms]\nover_pressure_mpa = 0.98\n' \
  >"$T/etc/conf.d/99-broken.toml"
kill -HUP "$DAEMON_PID"
for _ in $(seq 1 25); do
  [ "$(prop PressureSetpoint)" = "0.26" ] && break
  sleep 0.1
done
[ "$(prop PressureSetpoint)" = "0.26" ] || fail "live set-point not applied beside a safety limit"
grep -q "reload: alarms.over_pressure_mpa is a safety limit: restart required, running value kept" \
  "$T/daemon.log" || fail "kept safety limit not logged"
if "$SPRAYCTL" --user set-pressure 0.95 2>"$T/err.txt"; then
  fail "set-point 0.95 accepted: the reloaded trip was applied live"
fi
grep -q "outside 0.05..0.9 MPa" "$T/err.txt" || fail "$(cat "$T/err.txt")"
rm "$T/etc/conf.d/99-broken.toml"
echo "ok: a safety limit changed by reload waits for a restart"

# monitor prints changes, each with its time and unit.
timeout 2 "$SPRAYCTL" --user monitor >"$T/monitor.txt" || true
grep -qE "^[0-9]{2}:[0-9]{2}:[0-9]{2}\.[0-9]{3} (Pressure = [0-9.]+ MPa|Distance = [0-9.]+ m)$" "$T/monitor.txt" ||
  fail "monitor printed: $(head -3 "$T/monitor.txt")"
"$SPRAYCTL" --user clear-alarms || fail "ClearAlarms"
"$SPRAYCTL" --user stop || fail "Stop"
[ "$(prop State)" = '"Idle"' ] || fail "not Idle after Stop"
"$SPRAYCTL" --user start || fail "restart"
sleep 1

# SIGTERM while spraying: every valve closed, pump off, exit status 0.
kill -TERM "$DAEMON_PID"
rc=0
wait "$DAEMON_PID" || rc=$?
DAEMON_PID=
[ "$rc" -eq 0 ] || fail "exit status $rc after SIGTERM"
[ "$(cat "$T/valves.txt")" = "valves=0x0 pump=0" ] || fail "outputs at exit: $(cat "$T/valves.txt")"
grep -q "outputs safe" "$T/daemon.log" || fail "no 'outputs safe' line"
echo "ok: SIGTERM -> valves closed, pump off, exit 0"

# As-applied log and totals were written.
csv=$(ls "$T"/state/as-applied/as-applied-*.csv | head -1)
[ "$(wc -l <"$csv")" -gt 20 ] || fail "as-applied log too short: $csv"
grep -q "^area_m2 = " "$T/state/totals.toml" || fail "totals not saved"
area=$(sed -n 's/^area_m2 = //p' "$T/state/totals.toml")
echo "ok: as-applied log and totals ($area m^2)"

# Restart: totals restored (--resume: a simulation starts from zero otherwise); then a
# pressure-sensor wire breaks while spraying.
"$WEEDSPRAYD" --sim --user --config "$T/etc/weedspray.toml" --state-dir "$T/state" --resume \
  --valve-state-file "$T/valves.txt" --sim-fault sensor_open@4 >"$T/daemon.log" 2>&1 &
DAEMON_PID=$!
for _ in $(seq 1 100); do
  [ "$(prop State 2>/dev/null || true)" = '"Idle"' ] && break
  sleep 0.2
done
$PY -c "import sys; assert float(sys.argv[1]) >= float(sys.argv[2]) - 0.01 > 0, sys.argv" \
  "$(prop AreaCovered)" "$area" || fail "totals not restored: $(prop AreaCovered) < $area"
"$SPRAYCTL" --user monitor >"$T/monitor.txt" 2>&1 &
MONITOR_PID=$!
"$SPRAYCTL" --user start || fail "Start"
for _ in $(seq 1 50); do
  [ "$(prop State)" = '"Fault"' ] && break
  sleep 0.2
done
[ "$(prop State)" = '"Fault"' ] || fail "no Fault after the sensor wire broke"
expect_alarms pressure_sensor_fault
[ "$(prop NozzleDuty)" = "4 0 0 0 0" ] || fail "valves commanded open in Fault: $(prop NozzleDuty)"
if "$SPRAYCTL" --user start 2>/dev/null; then fail "Start accepted in Fault"; fi
sleep 0.5
kill "$MONITOR_PID"
grep -qE "^[0-9:.]{12} alarm-raised: pressure_sensor_fault$" "$T/monitor.txt" || fail "no AlarmRaised signal"
grep -q "alarm raised: pressure_sensor_fault (fault: valves closed, pump off; loop current .* - what to do: Check the sensor's wiring" "$T/daemon.log" ||
  fail "alarm not logged with its detail and remedy: $(grep 'alarm raised' "$T/daemon.log")"
# The catalog's severity, the condition (the wire stays cut) and the remedy, over the bus and on
# the first screen.
details="$(busctl --user get-property org.weedspray.Sprayer1 /org/weedspray/Sprayer1 \
  org.weedspray.Sprayer1 AlarmDetails)"
case "$details" in
  'a(ssbs) 1 "pressure_sensor_fault" "fault" true "Check the sensor'*) ;;
  *) fail "AlarmDetails: $details" ;;
esac
"$SPRAYCTL" --user status >"$T/status.txt"
grep -q "^  - pressure_sensor_fault (fault, condition present): Check the sensor's wiring" \
  "$T/status.txt" || fail "sprayctl status without the alarm's remedy: $(cat "$T/status.txt")"
kill -TERM "$DAEMON_PID"
rc=0
wait "$DAEMON_PID" || rc=$?
DAEMON_PID=
[ "$rc" -eq 0 ] || fail "exit status $rc after SIGTERM in Fault"
[ "$(cat "$T/valves.txt")" = "valves=0x0 pump=0" ] || fail "outputs at exit: $(cat "$T/valves.txt")"
echo "ok: sensor fault -> Fault, AlarmRaised, valves closed; totals restored"

# A Start sent the moment the bus name appears (before the loops have run) is kept, not refused.
"$WEEDSPRAYD" --sim --user --config "$T/etc/weedspray.toml" --state-dir "$T/state" \
  >"$T/daemon.log" 2>&1 &
DAEMON_PID=$!
started=0
for _ in $(seq 1 200); do
  if "$SPRAYCTL" --user start 2>"$T/err.txt"; then started=1; break; fi
  grep -q "refused" "$T/err.txt" && fail "early Start refused: $(cat "$T/err.txt")"
  sleep 0.05
done
[ "$started" = 1 ] || fail "Start never reached the daemon"
for _ in $(seq 1 50); do
  [ "$(prop State)" = '"Spraying"' ] && break
  sleep 0.1
done
[ "$(prop State)" = '"Spraying"' ] || fail "early Start: State $(prop State)"
kill -TERM "$DAEMON_PID"
wait "$DAEMON_PID" || fail "exit after the early Start"
DAEMON_PID=
echo "ok: a Start during start-up sprays once the loops run"
echo "PASS"
