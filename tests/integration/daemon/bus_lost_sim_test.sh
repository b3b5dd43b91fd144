#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The control link lost while spraying: the simulated sprayer sprays on a private bus, the bus
# daemon is killed, and weedsprayd stops by itself (valves closed, pump off) and exits with a
# failure status for systemd to restart it Idle. Without the disconnect watch it sprays on.
# usage: bus_lost_sim_test.sh BUILD_DIR
set -euo pipefail
BUILD=$(realpath "$1")
. "$(dirname "$0")/private_bus_lib.sh" bus-lost
WEEDSPRAYD="$BUILD/daemon/weedsprayd"
cat >"$T/weedspray.toml" <<'TOML'
[boom]
nozzles = 3
[spray]
decision_threshold = 0.0
[sim]
speed_profile = "constant"
speed_max_m_per_s = 1.0
TOML
start_private_bus
HOME="$T" start_sim_daemon --valve-state-file "$T/valves.txt"
call Start >/dev/null
wait_state Spraying 15
sleep 2
kill -KILL "$BUS_PID"
BUS_PID=
status=0
for _ in $(seq 1 50); do
  kill -0 "$DAEMON_PID" 2>/dev/null || break
  sleep 0.1
done
if kill -0 "$DAEMON_PID" 2>/dev/null; then
  fail "weedsprayd still runs 5 s after its bus died"
fi
wait "$DAEMON_PID" || status=$?
DAEMON_PID=
[ "$status" -ne 0 ] || fail "weedsprayd exited with status 0 after losing its bus"
grep -q "D-Bus connection lost" "$T/daemon.log" || fail "no log line names the lost bus"
grep -q "outputs safe: valves closed, pump off" "$T/daemon.log" || fail "outputs not made safe"
[ "$(cat "$T/valves.txt")" = "valves=0x0 pump=0" ] || fail "outputs at exit: $(cat "$T/valves.txt")"
echo "ok: bus killed while spraying -> stopped safely, exit status $status"
