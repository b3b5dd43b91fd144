#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Calibrations from the daemon: weedsprayd --sim (3 nozzles, nozzle 1 30 % blocked) on a private
# bus, driven with sprayctl and busctl:
#  1. refused while spraying; a catch test (sprayctl calibrate meter --seconds 2), refused
#     Start/CalibrateNozzles while it runs, then --volume with the litres the plant really
#     delivered (the sim logs them, as a user measures them): the meter's K found 2 % above the
#     configured one (the sim meter's K error), the MeterCalibration property says so;
#  2. sprayctl calibrate nozzles: progress reaches 1, each nozzle's line from the line meter,
#     nozzle 1's flow 30 % below the others';
#  3. a restart reloads both from the state directory's calibration.toml, and the volume the
#     daemon counts at the calibrated K matches the plant's true volume (at the configured K it
#     reads 2 % high).
# usage: calibration_sim_test.sh BUILD_DIR
set -euo pipefail
BUILD=$(realpath "$1")
WEEDSPRAYD=$BUILD/daemon/weedsprayd
SPRAYCTL=$BUILD/daemon/sprayctl
PY=/usr/bin/python3
. "$(dirname "$0")/private_bus_lib.sh" calibration
start_private_bus

cat >"$T/weedspray.toml" <<'TOML'
[boom]
nozzles = 3
[spray]
max_density = 0.05
decision_threshold = 0.005
[calibration]
duties_pct = [20.0, 50.0, 80.0]
# The pressure loop needs about 1 s after the switch to the next nozzle and duty, and a point
# wants a few PWM periods: with 0.2 s / 0.7 s the two healthy nozzles' 50 % flows differed by
# 0.92-1.04 on a loaded machine (a CI failure); with these, 0.974-0.983 (6 runs beside
# stress-ng --cpu 4).
settle_s = 1.0
measure_s = 1.4
min_r_squared = 0.95  # 1.4 s of one nozzle at 20 % is ~60 pulses: a coarse point
[sim]
# The ideal bench: its meter's K is 2 % above the label, the figure the catch test must find.
machine = "ideal"
speed_profile = "constant"
speed_max_m_per_s = 1.0
TOML
start_sim_daemon

# 1. The flow meter's catch test.
call Start
wait_state Spraying 5
if call StartCatchTest d 2 2>"$T/err.txt"; then fail "a catch test started while spraying"; fi
grep -q "refused: calibrations run in Idle" "$T/err.txt" || fail "$(cat "$T/err.txt")"
call Stop
wait_state Idle 5
call StartCatchTest d 2
if call Start 2>"$T/err.txt"; then fail "Start accepted during the catch test"; fi
if call CalibrateNozzles 2>"$T/err.txt"; then fail "a sweep started during the catch test"; fi
grep -q "a calibration is running" "$T/err.txt" || fail "$(cat "$T/err.txt")"
for _ in $(seq 1 10); do prop NozzleDuty | grep -q '^3 100 100 100$' && break; sleep 0.1; done
prop NozzleDuty | grep -q '^3 100 100 100$' || fail "catch test valves: $(prop NozzleDuty)"
for _ in $(seq 1 50); do
  prop Calibration | grep -q '^"awaiting_volume"' && break
  sleep 0.1
done
prop Calibration | grep -q '^"awaiting_volume"' || fail "catch test: $(prop Calibration)"
prop NozzleDuty | grep -q '^3 0 0 0$' || fail "valves after the catch test: $(prop NozzleDuty)"
litres=$(sed -n 's/.*sim: the catch test delivered \([0-9.]*\) L.*/\1/p' "$T/daemon.log" | tail -n1)
[ -n "$litres" ] || fail "no catch test volume in the log"
"$SPRAYCTL" --user calibrate meter --volume "$litres" >"$T/meter.txt" || fail "calibrate meter"
meter=$(prop MeterCalibration)
$PY - "$meter" <<'PY' || fail "MeterCalibration after the catch test: $meter ($(cat "$T/meter.txt"))"
import sys
source, k, configured, error = sys.argv[1].split()
assert source == '"calibration"', source
true_k = 8500 * 1.02  # the sim meter's K: 2 % above its label (sim/plant FlowMeterParams)
assert abs(float(k) / true_k - 1) < 0.005, k
assert float(configured) == 8500, configured
assert abs(float(error) - (8500 - true_k) / true_k * 100) < 0.5, error
PY
echo "ok: catch test of $litres L: $(cat "$T/meter.txt")"

# 2. The nozzles' lines, nozzle 1 30 % blocked.
call InjectSimFault s nozzle1_blocked_30
"$SPRAYCTL" --user calibrate nozzles >"$T/nozzles.txt" || fail "calibrate nozzles: $(cat "$T/nozzles.txt")"
prop Calibration | grep -q '^"done" 1 ' || fail "Calibration after the sweep: $(prop Calibration)"
lines=$(prop NozzleCalibration)
$PY - "$lines" <<'PY' || fail "NozzleCalibration: $lines"
import shlex, sys
f = shlex.split(sys.argv[1])
assert int(f[0]) == 3, f
rows = [f[1 + 4 * i: 5 + 4 * i] for i in range(3)]
flow = []
for source, a, b, r2 in rows:
    assert source == "calibration", rows
    assert float(r2) >= 0.95, rows
    flow.append(float(a) * 50 + float(b))  # L/min at 50 % duty
healthy = (flow[0] + flow[2]) / 2
assert abs(flow[0] / flow[2] - 1) < 0.08, flow
assert 0.6 < flow[1] / healthy < 0.8, flow  # 30 % blocked
print("flows at 50 %% duty: %s L/min; nozzle 0 / nozzle 2 %.4f, nozzle 1 / healthy %.4f"
      % (" ".join("%.4f" % q for q in flow), flow[0] / flow[2], flow[1] / healthy))
PY
echo "ok: nozzle lines: $(tr '\n' ';' <"$T/nozzles.txt")"
[ -f "$T/state/calibration.toml" ] || fail "no calibration.toml in the state directory"
# Each nozzle metered held open too (calibration.full_open, the default): stored with its line,
# at least the line's flow at the highest swept duty, the blocked nozzle's lower.
prop Calibration | grep -q "3 full-open flows" || fail "Calibration message: $(prop Calibration)"
$PY - "$T/state/calibration.toml" <<'PY' || fail "full-open flows in calibration.toml: $(cat "$T/state/calibration.toml")"
import sys, tomllib
nozzles = sorted(tomllib.load(open(sys.argv[1], "rb"))["nozzle"], key=lambda n: n["index"])
full = [n["full_open_flow_l_per_min"] for n in nozzles]
for n, q in zip(nozzles, full):
    assert q >= n["slope_l_per_min_per_pct"] * 80 + n["intercept_l_per_min"], (n, q)
assert 0.6 < full[1] / ((full[0] + full[2]) / 2) < 0.8, full  # 30 % blocked
print("held open: %s L/min" % " ".join("%.4f" % q for q in full))
PY
stop_daemon

# 3. After a restart: both reloaded; the calibrated K counts the true volume.
start_sim_daemon --sim-truth-file "$T/truth.txt"
[ "$(prop MeterCalibration)" = "$meter" ] || fail "meter after restart: $(prop MeterCalibration)"
[ "$(prop NozzleCalibration)" = "$lines" ] || fail "lines after restart: $(prop NozzleCalibration)"
call Start
sleep 3
call Stop
sleep 1
sprayed=$(prop VolumeSprayed)
stop_daemon
truth=$(sed -n 's/^sprayed_l=//p' "$T/truth.txt")
$PY -c "import sys; s, t = map(float, sys.argv[1:]); assert t > 0.05 and abs(s / t - 1) < 0.008, (s, t)" \
  "$sprayed" "$truth" || fail "VolumeSprayed $sprayed L, the plant sprayed $truth L"
echo "ok: after a restart: $sprayed L counted, $truth L sprayed"
echo PASS
