# SPDX-License-Identifier: Apache-2.0
# shellcheck shell=bash
# Sourced by the daemon's D-Bus test scripts: a scratch folder $T, removed at exit together with
# the daemon and the bus the script started ($DAEMON_PID, $BUS_PID) and whatever the script
# adds to EXIT_HOOKS (commands, run after the daemon is killed), fail() with the tails of the
# logs in FAIL_LOGS (default: $T/daemon.log), start_private_bus, prop/call/wait_state on the
# sprayer's object, start_sim_daemon and stop_daemon, calibrate_sim_machine; resumed_sim and
# wait_log for a daemon without a bus.
# usage: . private_bus_lib.sh NAME   ($T is /tmp/weedspray-NAME-test.XXXXXX; KEEP=1 keeps it)
T=$(mktemp -d "/tmp/weedspray-$1-test.XXXXXX")
DAEMON_PID=
BUS_PID=
EXIT_HOOKS=()
FAIL_LOGS=("$T/daemon.log")

cleanup() {
  [ -n "$DAEMON_PID" ] && kill -KILL "$DAEMON_PID" 2>/dev/null || true
  local hook
  for hook in "${EXIT_HOOKS[@]}"; do $hook || true; done
  [ -n "$BUS_PID" ] && kill "$BUS_PID" 2>/dev/null || true
  [ -n "${KEEP:-}" ] || rm -rf "$T"
}
trap cleanup EXIT

fail() {
  echo "FAIL: $*" >&2
  local log
  for log in "${FAIL_LOGS[@]}"; do
    [ -e "$log" ] || continue
    echo "--- $log (tail; status lines left out) ---" >&2
    grep -v "^Spraying\|^Idle" "$log" | tail -n 30 >&2 || true
  done
  exit 1
}

# A private session bus: never the host's.
start_private_bus() {
  dbus-daemon --session --fork --nopidfile --print-address=3 --print-pid=4 \
    3>"$T/bus.addr" 4>"$T/bus.pid"
  DBUS_SESSION_BUS_ADDRESS=$(cat "$T/bus.addr")
  export DBUS_SESSION_BUS_ADDRESS
  BUS_PID=$(cat "$T/bus.pid")
}

# The sprayer's D-Bus object on that bus (scripts set DAEMON_PID before wait_state).
prop() {  # prop NAME -> value as busctl prints it, without the type signature
  busctl --user get-property org.weedspray.Sprayer1 /org/weedspray/Sprayer1 \
    org.weedspray.Sprayer1 "$1" | cut -d' ' -f2-
}
expect_alarms() {  # expect_alarms [NAME...]: Alarms holds these, and besides them at most
  # control_overruns, the warning a loaded test machine's late control cycles raise
  local alarms
  alarms=$(prop Alarms)
  /usr/bin/python3 - "$alarms" "$@" <<'PYEOF' || fail "Alarms: $alarms, expected: ${*:-none}"
import shlex, sys
items = set(shlex.split(sys.argv[1])[1:]) - {"control_overruns"}
assert items == set(sys.argv[2:]), items
PYEOF
}

call() {  # call METHOD [SIGNATURE ARGS...]
  busctl --user call org.weedspray.Sprayer1 /org/weedspray/Sprayer1 org.weedspray.Sprayer1 "$@"
}
# $T/weedspray.toml for the sim: spraying from the start (daemon.autostart), 3 nozzles, then
# the TOML lines given.
write_sim_config() {  # write_sim_config [TOML LINE...]
  printf '%s\n' "[daemon]" "autostart = true" "[boom]" "nozzles = 3" "$@" >"$T/weedspray.toml"
}
# $T/weedspray.toml for the sim: 3 nozzles driven at a constant 1 m/s, then the TOML lines given.
write_constant_speed_config() {  # write_constant_speed_config [TOML LINE...]
  printf '%s\n' "[boom]" "nozzles = 3" "[sim]" 'speed_profile = "constant"' \
    "speed_max_m_per_s = 1.0" "$@" >"$T/weedspray.toml"
}
# weedsprayd --sim without a bus on $T/weedspray.toml and the state folder $T/state, with
# --resume as a restart does, logging to $T/NAME.log (BUILD set by the script). It execs the
# daemon: after `resumed_sim NAME &`, $! is the daemon itself (a kill reaches it, not a
# subshell); `(resumed_sim NAME ARGS...)` waits for it and returns its status.
resumed_sim() {  # resumed_sim NAME [WEEDSPRAYD ARGS...]
  local name=$1
  shift
  HOME="$T" exec "$BUILD/daemon/weedsprayd" --sim --no-bus --resume --config "$T/weedspray.toml" \
    --state-dir "$T/state" "$@" >"$T/$name.log" 2>&1
}
wait_log() {  # wait_log FILE PATTERN [TENTHS]: until FILE has a line matching PATTERN (15 s)
  local _
  for _ in $(seq 1 "${3:-150}"); do
    grep -q "$2" "$1" 2>/dev/null && return 0
    sleep 0.1
  done
  fail "$(basename "$1"): never logged: $2"
}

# weedsprayd --sim on $T/weedspray.toml with its state in $T/state, logging to $T/daemon.log,
# until Idle (WEEDSPRAYD set by the script).
start_sim_daemon() {  # start_sim_daemon [WEEDSPRAYD ARGS...]
  mkdir -p "$T/state"
  "$WEEDSPRAYD" --sim --user --config "$T/weedspray.toml" --state-dir "$T/state" "$@" \
    >>"$T/daemon.log" 2>&1 &
  DAEMON_PID=$!
  wait_state Idle 15
}
stop_daemon() {  # SIGTERM; fails unless weedsprayd exits with status 0
  kill -TERM "$DAEMON_PID"
  wait "$DAEMON_PID" || fail "weedsprayd exit status $?"
  DAEMON_PID=
}
wait_state() {  # wait_state STATE SECONDS
  local state
  for _ in $(seq 1 $(($2 * 10))); do
    state=$(prop State 2>/dev/null || true)
    [ "$state" = "\"$1\"" ] && return 0
    kill -0 "$DAEMON_PID" 2>/dev/null || fail "weedsprayd exited"
    sleep 0.1
  done
  fail "State is '$state', expected $1"
}
calibrate_sim_machine() {  # a 2 s catch test with the volume the plant delivered, then the nozzles
  call StartCatchTest d 2
  for _ in $(seq 1 80); do
    prop Calibration | grep -q '^"awaiting_volume"' && break
    sleep 0.1
  done
  local litres
  litres=$(sed -n 's/.*sim: the catch test delivered \([0-9.]*\) L.*/\1/p' "$T/daemon.log" | tail -n1)
  [ -n "$litres" ] || fail "no catch test volume in the log: $(prop Calibration)"
  "$BUILD/daemon/sprayctl" --user calibrate meter --volume "$litres" >/dev/null || fail "calibrate meter"
  "$BUILD/daemon/sprayctl" --user calibrate nozzles >"$T/nozzles.txt" ||
    fail "calibrate nozzles: $(cat "$T/nozzles.txt")"
}
