#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Nozzle health while spraying: weedsprayd --sim (4 nozzles, [nozzle_health] on, a 20 s
# baseline) on a private bus:
#  1. healthy: the baseline is learned while spraying and no nozzle_flow_fault is raised;
#  2. InjectSimFault nozzle2_blocked_30: nozzle_flow_fault within 10 s, the log names nozzle 2
#     (0-based, as NozzleDuty and the sim fault count), its NozzleHealth ratio is (or within
#     10 s more becomes) the lowest and below 0.88; the daemon keeps spraying (a warning: the
#     valves stay driven);
#  3. ClearAlarms (after a clean) restarts the baseline: no alarm, ratios 1 while relearning.
# usage: nozzle_health_sim_test.sh BUILD_DIR
set -euo pipefail
BUILD=$(realpath "$1")
WEEDSPRAYD=$BUILD/daemon/weedsprayd
PY=/usr/bin/python3
. "$(dirname "$0")/private_bus_lib.sh" nozzle-health
start_private_bus


cat >"$T/weedspray.toml" <<'TOML'
[boom]
nozzles = 4
[spray]
decision_threshold = 0.005
[nozzle_health]
enabled = true
baseline_s = 20.0
[sim]
speed_profile = "constant"
speed_max_m_per_s = 1.0
TOML
start_sim_daemon
call Start
wait_state Spraying 5

# 1. Healthy: the baseline takes 20 s of spraying; then a few seconds judged without an alarm.
# HEALTHY_S (seconds of healthy spraying, default 26) longer: the README's false-alarm figure.
for i in $(seq 1 "${HEALTHY_S:-26}"); do
  sleep 1
  echo "t=$i s NozzleHealth $(prop NozzleHealth) NozzleDuty $(prop NozzleDuty)" >>"$T/healthy.txt"
done
prop Alarms | grep -q nozzle_flow_fault && fail "nozzle_flow_fault on a healthy machine: $(prop NozzleHealth)"
$PY - "$T/healthy.txt" <<'PY'
import sys
judged = [[float(x) for x in line.split()[4:8]] for line in open(sys.argv[1])]
judged = [r for r in judged if r != [1.0] * 4]  # the baseline learned
dev = max((abs(x - 1) for r in judged for x in r), default=float("nan"))
print(f"healthy: {len(judged)} s judged, largest |ratio - 1| seen {dev:.3f} (alarm above 0.12 with judge = band)")
PY
healthy=$(prop NozzleHealth)
$PY - "$healthy" <<'PY' || fail "NozzleHealth on a healthy machine: $healthy"
import sys
f = sys.argv[1].split()
assert int(f[0]) == 4, f
ratios = [float(x) for x in f[1:]]
assert all(r != 1.0 for r in ratios), ("baseline never learned", ratios)
assert all(abs(r - 1) < 0.12 for r in ratios), ratios
PY
echo "ok: healthy, baseline learned: NozzleHealth $healthy"

# 2. Nozzle 2 blocked 30 %.
call InjectSimFault s nozzle2_blocked_30
start=$(date +%s.%N)
for _ in $(seq 1 100); do
  prop Alarms | grep -q nozzle_flow_fault && break
  sleep 0.1
done
named=$(date +%s.%N)
prop Alarms | grep -q nozzle_flow_fault || fail "no nozzle_flow_fault 10 s after the blockage: $(prop NozzleHealth)"
grep -q "alarm raised: nozzle_flow_fault (warning; nozzle 2: blocked" "$T/daemon.log" ||
  fail "the alarm does not name nozzle 2: $(grep nozzle_flow_fault "$T/daemon.log")"
# With judge = "cusum" the alarm usually comes before the shown ratio (6 s forgetting) has moved
# all the way: that ratio must follow within 10 s more (with "band" it already has).
for _ in $(seq 1 100); do
  blocked=$(prop NozzleHealth)
  $PY - "$blocked" 2>/dev/null <<'PY' && break
import sys
ratios = [float(x) for x in sys.argv[1].split()[1:]]
assert ratios[2] < 0.88 and ratios[2] == min(ratios), ratios
PY
  sleep 0.1
done
$PY - "$blocked" <<'PY' || fail "NozzleHealth with nozzle 2 blocked: $blocked"
import sys
ratios = [float(x) for x in sys.argv[1].split()[1:]]
assert ratios[2] < 0.88 and ratios[2] == min(ratios), ratios
PY
"$BUILD/daemon/sprayctl" --user status >"$T/status.txt"
grep -q "^Nozzle health: [0-9.]* [0-9.]* 0\.[0-8]" "$T/status.txt" ||
  fail "sprayctl status: $(grep -i health "$T/status.txt")"
[ "$(prop State)" = '"Spraying"' ] || fail "State $(prop State) after a nozzle_flow_fault (a warning)"
echo "ok: nozzle_flow_fault named nozzle 2 after $($PY -c "import sys; print(f'{float(sys.argv[2]) - float(sys.argv[1]):.1f}')" "$start" "$named") s: NozzleHealth $blocked"

# 3. ClearAlarms (the nozzle cleaned): the detector learns a new baseline, the alarm stays off.
call InjectSimFault s nozzle2_ok
call ClearAlarms
sleep 1
prop Alarms | grep -q nozzle_flow_fault && fail "nozzle_flow_fault back after ClearAlarms"
[ "$(prop NozzleHealth)" = "4 1 1 1 1" ] || fail "NozzleHealth after ClearAlarms: $(prop NozzleHealth)"
echo "ok: ClearAlarms restarts the baseline"
echo PASS
