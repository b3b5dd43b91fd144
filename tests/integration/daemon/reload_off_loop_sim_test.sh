#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# A reload reads the files and probes the model on a thread of its own: the simulated sprayer
# sprays on a private bus while a reload is made to take 3 s (WEEDSPRAY_TEST_RELOAD_DELAY_MS);
# meanwhile its properties keep answering within 1 s and keep moving (the main loop runs), and
# `sprayctl reload` returns once the new set-point is applied. A second reload asked while the
# first runs reads the files as they are after it; a broken file is still refused over the bus.
# usage: reload_off_loop_sim_test.sh BUILD_DIR
set -euo pipefail
BUILD=$(realpath "$1")
. "$(dirname "$0")/private_bus_lib.sh" reload-off-loop
WEEDSPRAYD="$BUILD/daemon/weedsprayd"
SPRAYCTL="$BUILD/daemon/sprayctl"
mkdir -p "$T/conf.d"
write_constant_speed_config
start_private_bus
export WEEDSPRAY_TEST_RELOAD_DELAY_MS=3000
HOME="$T" start_sim_daemon
call Start >/dev/null
wait_state Spraying 15

printf '[pressure]\nsetpoint_mpa = 0.25\n' >"$T/conf.d/50-setpoint.toml"
started=$(date +%s%N)
"$SPRAYCTL" --user reload >"$T/reload.log" 2>&1 &
reload_pid=$!
sleep 0.5
# While the reload runs: each read answers within 1 s, and Distance grows.
slowest_ms=0
first=$(prop Distance)
for _ in 1 2 3 4; do
  t0=$(date +%s%N)
  prop State >/dev/null
  ms=$((($(date +%s%N) - t0) / 1000000))
  [ "$ms" -gt "$slowest_ms" ] && slowest_ms=$ms
  sleep 0.3
done
last=$(prop Distance)
kill -0 "$reload_pid" 2>/dev/null || fail "the reload was over before the main loop was judged"
[ "$slowest_ms" -lt 1000 ] || fail "a property read took $slowest_ms ms during the reload"
awk -v a="$first" -v b="$last" 'BEGIN { exit !(b > a) }' ||
  fail "Distance stood still during the reload ($first -> $last): the main loop was blocked"
# A second request while the first runs: it waits for a job that reads the files after it.
printf '[pressure]\nsetpoint_mpa = 0.2\n' >"$T/conf.d/50-setpoint.toml"
"$SPRAYCTL" --user reload >"$T/reload2.log" 2>&1 || fail "second reload: $(cat "$T/reload2.log")"
wait "$reload_pid" || fail "reload: $(cat "$T/reload.log")"
took_ms=$((($(date +%s%N) - started) / 1000000))
[ "$took_ms" -ge 3000 ] || fail "the reload returned after $took_ms ms, before its 3 s delay"
[ "$(prop PressureSetpoint)" = "0.2" ] || fail "set-point $(prop PressureSetpoint) after both reloads"
[ "$(prop State)" = '"Spraying"' ] || fail "State $(prop State) after the reloads"
echo "ok: reads answered within $slowest_ms ms and Distance went $first -> $last during a 3 s reload"

# A broken file: refused over the bus, naming it, the running configuration kept.
printf '[pressure]\nsetpoint_mpa = 7\n' >"$T/conf.d/50-setpoint.toml"
if "$SPRAYCTL" --user reload 2>"$T/err.txt"; then fail "a broken reload was accepted"; fi
grep -q "50-setpoint.toml:2: pressure.setpoint_mpa: 7 is outside" "$T/err.txt" ||
  fail "reload error: $(cat "$T/err.txt")"
[ "$(prop PressureSetpoint)" = "0.2" ] || fail "a refused reload changed the set-point"
stop_daemon
echo "PASS"
