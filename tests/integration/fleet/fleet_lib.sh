# SPDX-License-Identifier: Apache-2.0
# shellcheck shell=bash
# Sourced by the fleet tests: a machine of simulated boards on a loopback MQTT broker.
# A scratch folder $T (removed at exit with every process started here; KEEP=1 keeps it),
# fail() with the logs' tails, start_broker (mosquitto on a free loopback port, private
# config: $PORT), start_board N (weedsprayd --sim on a private session bus of its own, since
# each daemon owns the one well-known name), start_bridge N (weedspray-fleet for board N),
# board_prop N NAME, wait_board_prop N NAME VALUE SECONDS, wait_board_state N STATE SECONDS,
# wait_board_closed N SECONDS (Idle, duties 0), wait_all_spraying T0 WHAT (BOARDS, within 1 s),
# retained TOPIC (its retained payload), wait_retained TOPIC REGEX SECONDS, publish TOPIC PAYLOAD.
# usage: BUILD=... ; . fleet_lib.sh NAME
T=$(mktemp -d "/tmp/weedspray-$1-test.XXXXXX")
MACHINE=testmachine
PIDS=()
declare -A BUS DAEMON_PID BRIDGE_PID

cleanup() {
  local pid
  # TERM first: Chromium then ends its own child processes, which would otherwise write into
  # its profile under $T while it is being removed.
  for pid in "${PIDS[@]}"; do kill -TERM "$pid" 2>/dev/null || true; done
  sleep 0.5
  for pid in "${PIDS[@]}"; do kill -KILL "$pid" 2>/dev/null || true; done
  [ -n "${KEEP:-}" ] || rm -rf "$T"
}
trap cleanup EXIT

fail() {
  echo "FAIL: $*" >&2
  local log
  for log in "$T"/*.log; do
    [ -e "$log" ] || continue
    echo "--- $log (tail) ---" >&2
    grep -v "^Spraying\|^Idle" "$log" | tail -n 15 >&2 || true
  done
  exit 1
}

now() { date +%s.%N; }
elapsed_since() { /usr/bin/python3 -c "import sys,time; print(f'{time.time()-float(sys.argv[1]):.3f}')" "$1"; }

start_broker() {
  PORT=$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])')
  printf '%s\n' "listener $PORT 127.0.0.1" "allow_anonymous true" "persistence false" \
    "log_dest stderr" >"$T/mosquitto.conf"
  restart_broker
}

restart_broker() {  # mosquitto on $PORT again (after start_broker), until it answers
  "$(command -v mosquitto || echo /usr/sbin/mosquitto)" -c "$T/mosquitto.conf" >>"$T/mosquitto.log" 2>&1 &
  BROKER_PID=$!
  PIDS+=($!)
  local _
  for _ in $(seq 1 50); do
    mosquitto_pub -h 127.0.0.1 -p "$PORT" -t weedspray/probe -n 2>/dev/null && return 0
    sleep 0.1
  done
  fail "mosquitto never listened on port $PORT"
}

# Field frames all green (SIM_IMAGES, the boards' camera): every zone is weed, so a spraying
# board's duties are above 0. Without it the boards see the bundled field images.
make_green_field() {
  SIM_IMAGES="$T/images"
  mkdir -p "$T/images"
  /usr/bin/python3 - "$T/images/field.png" "$SOURCE/tests/integration/daemon" <<'PYEOF'
import sys
sys.path.insert(0, sys.argv[2])
from png_file import write_png
write_png(sys.argv[1], 160, 100, lambda x, y: (60, 150, 40))
PYEOF
}

# $T/bN/weedspray.toml: 3 nozzles at a constant 1 m/s, [fleet] for the broker, then the TOML
# lines given.
write_board_config() {  # write_board_config N [TOML LINE...]
  local n=$1
  shift
  mkdir -p "$T/b$n/state"
  printf '%s\n' "[boom]" "nozzles = 3" "[sim]" 'speed_profile = "constant"' \
    "speed_max_m_per_s = 1.0" "[fleet]" "enabled = true" "port = $PORT" \
    "machine = \"$MACHINE\"" "board = \"b$n\"" "first_nozzle_offset_m = $((n * 3)).0" \
    "picture_interval_s = 1" "$@" >"$T/b$n/weedspray.toml"
}

start_board() {  # start_board N: its daemon on a bus of its own, until Idle
  local n=$1
  dbus-daemon --session --fork --nopidfile --print-address=3 --print-pid=4 \
    3>"$T/b$n/bus.addr" 4>"$T/b$n/bus.pid"
  BUS[$n]=$(cat "$T/b$n/bus.addr")
  PIDS+=("$(cat "$T/b$n/bus.pid")")
  DBUS_SESSION_BUS_ADDRESS=${BUS[$n]} "$BUILD/daemon/weedsprayd" --sim --user \
    --config "$T/b$n/weedspray.toml" --state-dir "$T/b$n/state" \
    ${SIM_IMAGES:+--sim-images "$SIM_IMAGES"} \
    >"$T/daemon$n.log" 2>&1 &
  DAEMON_PID[$n]=$!
  PIDS+=($!)
}

start_bridge() {  # start_bridge N
  local n=$1
  DBUS_SESSION_BUS_ADDRESS=${BUS[$n]} "$BUILD/fleet/weedspray-fleet" --user \
    --config "$T/b$n/weedspray.toml" >"$T/bridge$n.log" 2>&1 &
  BRIDGE_PID[$n]=$!
  PIDS+=($!)
}

board_prop() {  # board_prop N NAME -> the value as busctl prints it, without its type
  DBUS_SESSION_BUS_ADDRESS=${BUS[$1]} busctl --user get-property org.weedspray.Sprayer1 \
    /org/weedspray/Sprayer1 org.weedspray.Sprayer1 "$2" 2>/dev/null | cut -d' ' -f2-
}

wait_board_prop() {  # wait_board_prop N NAME VALUE SECONDS: until board_prop prints VALUE
  local value _
  for _ in $(seq 1 $(($4 * 10))); do
    value=$(board_prop "$1" "$2" || true)
    [ "$value" = "$3" ] && return 0
    sleep 0.1
  done
  fail "board $1: $2 is '$value', expected '$3' within $4 s"
}
wait_board_state() { wait_board_prop "$1" State "\"$2\"" "$3"; }  # N STATE SECONDS
wait_board_closed() {  # wait_board_closed N SECONDS: Idle, every nozzle's duty 0
  wait_board_state "$1" Idle "$2"
  wait_board_prop "$1" NozzleDuty "3 0 0 0" "$2"
}

# Every board in BOARDS Spraying within 1 s of T0 (over D-Bus); sets $took.
wait_all_spraying() {  # wait_all_spraying T0 WHAT
  local pending=" ${BOARDS[*]} " n
  while [ -n "${pending// /}" ]; do
    for n in $pending; do
      [ "$(board_prop "$n" State)" = '"Spraying"' ] && pending=${pending/ $n / }
    done
    took=$(elapsed_since "$1")
    /usr/bin/python3 -c "import sys; sys.exit(float(sys.argv[1]) > 1.0)" "$took" ||
      fail "boards$pending not Spraying 1 s after $2"
  done
}

retained() {  # retained TOPIC -> its retained payload ("" when none within 2 s)
  mosquitto_sub -h 127.0.0.1 -p "$PORT" -t "$1" -C 1 -W 2 2>/dev/null || true
}

wait_retained() {  # wait_retained TOPIC PAYLOAD_REGEX SECONDS
  local payload _
  for _ in $(seq 1 $(($3 * 5))); do
    payload=$(mosquitto_sub -h 127.0.0.1 -p "$PORT" -t "$1" -C 1 -W 1 2>/dev/null || true)
    [[ "$payload" =~ $2 ]] && return 0
    sleep 0.2
  done
  fail "$1 is '$payload', expected /$2/ within $3 s"
}

retained_picture() {  # retained_picture N FILE: board N's retained picture, a PNG -> "W H"
  local _
  for _ in $(seq 1 10); do
    mosquitto_sub -h 127.0.0.1 -p "$PORT" -t "weedspray/$MACHINE/b$1/picture" --retained-only \
      -N -C 1 -W 1 >"$2" 2>/dev/null || true
    [ -s "$2" ] && break
  done
  [ -s "$2" ] || fail "board $1: no picture retained within 10 s"
  $PY - "$2" <<'PYEOF' || fail "board $1: the retained picture is not a PNG"
import struct, sys
png = open(sys.argv[1], "rb").read()
assert png[:8] == b"\x89PNG\r\n\x1a\n" and png[12:16] == b"IHDR", png[:16]
width, height = struct.unpack(">II", png[16:24])
assert width > 0 and height > 0, (width, height)
print(width, height)
PYEOF
}

publish() {  # publish TOPIC PAYLOAD
  mosquitto_pub -h 127.0.0.1 -p "$PORT" -q 1 -t "$1" -m "$2"
}
