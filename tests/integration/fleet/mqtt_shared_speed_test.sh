#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Shared speed over a loopback mosquitto: board 1 owns the speed (its simulated wheel at
# 1.7 m/s, fleet.motion_rate_hz = 20), board 2 takes it (speed.source = "fleet",
# fleet.speed_from = "b1"; its own simulated ground at 0.6 m/s). Board 2's Speed and Distance
# follow board 1's; both spray. Board 1's bridge killed: board 2's valves closed and
# shared_speed_lost raised within speed.shared_timeout_s + 1 s. The bridge back: SpeedSource
# "fleet" again, and after ClearAlarms board 2 sprays. Board 2's broker connection lost (with
# fleet.on_broker_lost = "continue", so the bridge does not stop it): the same closed state.
# usage: mqtt_shared_speed_test.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
BUILD=$(realpath "$1")
SOURCE=$(realpath "$2")
PY=/usr/bin/python3
. "$(dirname "$0")/fleet_lib.sh" shared-speed
BOARDS=(1 2)
TIMEOUT_S=0.5

start_broker
make_green_field
write_board_config 1 'motion_rate_hz = 20'
sed -i 's/^speed_max_m_per_s = .*/speed_max_m_per_s = 1.7/' "$T/b1/weedspray.toml"
write_board_config 2 'speed_from = "b1"' 'on_broker_lost = "continue"' '[speed]' \
  'source = "fleet"' "shared_timeout_s = $TIMEOUT_S"
sed -i 's/^speed_max_m_per_s = .*/speed_max_m_per_s = 0.6/' "$T/b2/weedspray.toml"
for n in "${BOARDS[@]}"; do start_board "$n"; done
for n in "${BOARDS[@]}"; do wait_board_state "$n" Idle 30; done
for n in "${BOARDS[@]}"; do start_bridge "$n"; done

# Board 2 takes board 1's speed and odometer, not its own ground's.
wait_board_prop 2 SpeedSource '"fleet"' 10
for _ in $(seq 1 50); do
  speed=$(board_prop 2 Speed)
  $PY -c "import sys; sys.exit(abs(float(sys.argv[1]) - 1.7) > 0.05)" "$speed" && break
  sleep 0.1
done
$PY -c "import sys; sys.exit(abs(float(sys.argv[1]) - 1.7) > 0.05)" "$speed" ||
  fail "board 2's Speed is $speed, board 1's 1.7 m/s"
sleep 3  # the two odometers apart by 3.3 m if board 2 ran on its own ground
d1=$(board_prop 1 Distance)
d2=$(board_prop 2 Distance)
$PY -c "import sys; sys.exit(abs(float(sys.argv[1]) - float(sys.argv[2])) > 1.0)" "$d1" "$d2" ||
  fail "board 2's Distance $d2 m does not follow board 1's $d1 m"
echo "ok: board 2's Speed $speed m/s and Distance $d2 m follow board 1's ($d1 m)"
# The motion topic is not retained: a board that connects later gets no stale sample.
[ -z "$(mosquitto_sub -h 127.0.0.1 -p "$PORT" -t "weedspray/$MACHINE/b1/motion" --retained-only \
  -C 1 -W 1 2>/dev/null || true)" ] || fail "board 1's motion is retained"
echo "ok: motion published, not retained"

spray_both() {  # start on the machine's topic: both boards Spraying, board 2's duties above 0
  local t0 duties _
  t0=$(now)
  publish "weedspray/$MACHINE/cmd" '{"command":"start","id":"go"}'
  wait_all_spraying "$t0" "start"
  for _ in $(seq 1 50); do
    duties=$(board_prop 2 NozzleDuty)
    $PY -c "import sys; sys.exit(max(map(float, sys.argv[1].split()[1:])) <= 0)" "$duties" && return 0
    sleep 0.1
  done
  fail "board 2 duties $duties while spraying"
}

# Board 2 closed and shared_speed_lost raised within the timeout + 1 s of T0.
wait_shared_speed_lost() {  # wait_shared_speed_lost T0 WHAT
  local alarms duties state _
  for _ in $(seq 1 40); do
    alarms=$(board_prop 2 Alarms)
    duties=$(board_prop 2 NozzleDuty)
    state=$(board_prop 2 State)
    if [[ "$alarms" == *'"shared_speed_lost"'* && "$duties" == "3 0 0 0" && "$state" == '"Fault"' ]]; then
      took=$(elapsed_since "$1")
      $PY -c "import sys; sys.exit(float(sys.argv[1]) > float(sys.argv[2]) + 1)" "$took" "$TIMEOUT_S" ||
        fail "board 2 closed only $took s after $2"
      return 0
    fi
    sleep 0.05
  done
  fail "board 2 after $2: alarms $alarms, duties $duties, state $state"
}

spray_both
echo "ok: both boards spraying on board 1's speed"
t0=$(now)
kill -KILL "${BRIDGE_PID[1]}"
wait_shared_speed_lost "$t0" "board 1's bridge was killed"
echo "ok: board 2 closed, shared_speed_lost raised $took s after board 1's bridge was killed"
[ "$(board_prop 2 SpeedSource)" = '"fleet (samples lost)"' ] ||
  fail "board 2's SpeedSource: $(board_prop 2 SpeedSource)"
[ "$(board_prop 1 State)" = '"Spraying"' ] || fail "board 1 stopped: $(board_prop 1 State)"

# The owner's bridge back: samples again; once the alarms are cleared board 2 sprays again.
start_bridge 1
wait_board_prop 2 SpeedSource '"fleet"' 10
publish "weedspray/$MACHINE/b2/cmd" '{"command":"clear_alarms"}'
wait_board_state 2 Idle 5
spray_both
echo "ok: samples back, alarms cleared: board 2 sprays again"

# Board 2's own broker connection lost: its bridge stops feeding; the same closed state.
t0=$(now)
kill -KILL "$BROKER_PID"
wait_shared_speed_lost "$t0" "the broker was killed"
echo "ok: board 2 closed, shared_speed_lost raised $took s after the broker was killed"
