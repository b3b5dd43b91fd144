#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The line monitors during a calibration: weedsprayd --sim (3 nozzles) on a private bus runs a
# catch test (every valve open, the pump on in Idle); the pump's filter blocks: no_flow is
# raised as it is while spraying, the sprayer goes to Fault, the catch test is cancelled, its
# valves closed, and Start is refused until the alarm is cleared.
# usage: calibration_fault_sim_test.sh BUILD_DIR
set -euo pipefail
BUILD=$(realpath "$1")
WEEDSPRAYD=$BUILD/daemon/weedsprayd
. "$(dirname "$0")/private_bus_lib.sh" calibration-fault
start_private_bus

write_constant_speed_config
start_sim_daemon --valve-state-file "$T/valves.txt"

call StartCatchTest d 60
for _ in $(seq 1 30); do prop NozzleDuty | grep -q '^3 100 100 100$' && break; sleep 0.1; done
prop NozzleDuty | grep -q '^3 100 100 100$' || fail "catch test valves: $(prop NozzleDuty)"
sleep 1  # the pump at its set-point, the line flowing
expect_alarms  # none before the fault
call InjectSimFault s filter_blocked
wait_state Fault 10
expect_alarms no_flow
prop Calibration | grep -q '^"cancelled"' || fail "Calibration in Fault: $(prop Calibration)"
# The status published with the Fault may carry the control loop's cycle before it.
for _ in $(seq 1 10); do [ "$(prop NozzleDuty)" = "3 0 0 0" ] && break; sleep 0.1; done
[ "$(prop NozzleDuty)" = "3 0 0 0" ] || fail "valves commanded open in Fault: $(prop NozzleDuty)"
if call Start 2>/dev/null; then fail "Start accepted in Fault"; fi
grep -q "alarm raised: no_flow (fault: valves closed, pump off)" "$T/daemon.log" ||
  fail "alarm not logged"
stop_daemon
[ "$(cat "$T/valves.txt")" = "valves=0x0 pump=0" ] || fail "outputs at exit: $(cat "$T/valves.txt")"
echo "ok: a blocked filter during the catch test -> no_flow, Fault, catch test cancelled"
