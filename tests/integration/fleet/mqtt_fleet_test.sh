#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Three weedsprayd --sim boards joined into one machine over a loopback mosquitto, one
# weedspray-fleet bridge each (each board on a private session bus of its own): their state
# appears retained on the broker; "start" on the machine's command topic makes every board
# spray within 1 s (State and duties over D-Bus); a malformed and an unauthorised command are
# refused with a reply and counted; "rate" and "threshold" reach every board's D-Bus properties,
# and a dose the daemon refuses comes back in the reply, counted as failed; "stop" closes every
# valve; a killed bridge and a killed daemon each turn their board's online to false, and a
# board set to stop when another is lost stops while one set to continue sprays on; a board
# whose broker is lost stops, and reconnects once it is back; a bridge that stops says goodbye
# the same way; every board's live-view picture is retained, a PNG.
# usage: mqtt_fleet_test.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
BUILD=$(realpath "$1")
SOURCE=$(realpath "$2")
PY=/usr/bin/python3
. "$(dirname "$0")/fleet_lib.sh" mqtt
BOARDS=(1 2 3)

start_broker
make_green_field
write_board_config 1 'on_board_lost = "stop"'
write_board_config 2
write_board_config 3
for n in "${BOARDS[@]}"; do start_board "$n"; done
for n in "${BOARDS[@]}"; do wait_board_state "$n" Idle 30; done
for n in "${BOARDS[@]}"; do start_bridge "$n"; done

# Retained state: a newcomer sees every board's last values at once.
for n in "${BOARDS[@]}"; do
  wait_retained "weedspray/$MACHINE/b$n/online" '^true$' 10
  wait_retained "weedspray/$MACHINE/b$n/state" '"state":"Idle"' 5
  info=$(retained "weedspray/$MACHINE/b$n/info")
  $PY - "$info" "$n" <<'PYEOF' || fail "board $n info: $info"
import json, sys
info = json.loads(sys.argv[1])
assert info["board"] == "b" + sys.argv[2] and info["nozzles"] == 3, info
assert info["first_nozzle_offset_m"] == 3.0 * int(sys.argv[2]), info
PYEOF
  for leaf in alarms nozzles pressure flow speed tank health commands; do
    [ -n "$(retained "weedspray/$MACHINE/b$n/$leaf")" ] || fail "board $n: nothing retained on $leaf"
  done
done
echo "ok: every board's state retained on the broker"
# The live-view picture (picture_interval_s = 1): camera 0's PNG, retained, on every board.
for n in "${BOARDS[@]}"; do
  size=$(retained_picture "$n" "$T/picture$n.png")
  echo "ok: board $n picture retained: $size px, $(stat -c %s "$T/picture$n.png") bytes"
done

# Start on the machine's topic: every board sprays within 1 s.
t0=$(now)
publish "weedspray/$MACHINE/cmd" '{"command":"start","id":"go"}'
wait_all_spraying "$t0" "start on weedspray/$MACHINE/cmd"
echo "ok: every board Spraying ${took} s after start on weedspray/$MACHINE/cmd"
# The valves follow the (all-green) field: duties above 0 on every board.
for n in "${BOARDS[@]}"; do
  for _ in $(seq 1 50); do
    duties=$(board_prop "$n" NozzleDuty)
    $PY -c "import sys; sys.exit(max(map(float, sys.argv[1].split()[1:])) <= 0)" "$duties" && break
    sleep 0.1
  done
  $PY -c "import sys; sys.exit(max(map(float, sys.argv[1].split()[1:])) <= 0)" "$duties" ||
    fail "board $n duties $duties while spraying"
done
wait_retained "weedspray/$MACHINE/b1/state" '"state":"Spraying"' 3
echo "ok: every board's duties above 0"

# A malformed and an unauthorised command (reload_config is an admin command; the bridge
# takes operator commands): refused with a reply naming why, counted, and the board sprays on.
mosquitto_sub -h 127.0.0.1 -p "$PORT" -t "weedspray/$MACHINE/b1/reply" -C 2 -W 10 \
  >"$T/replies.txt" &
PIDS+=($!)
replies_pid=$!
sleep 0.5
publish "weedspray/$MACHINE/b1/cmd" 'start please'
publish "weedspray/$MACHINE/b1/cmd" '{"command":"reload_config","id":"r1"}'
wait "$replies_pid" || fail "no two replies: $(cat "$T/replies.txt")"
grep -q '"ok":false.*"reason":"malformed"' "$T/replies.txt" || fail "replies: $(cat "$T/replies.txt")"
grep -q '"id":"r1".*"ok":false.*"reason":"unauthorised"' "$T/replies.txt" ||
  fail "replies: $(cat "$T/replies.txt")"
counters=$(retained "weedspray/$MACHINE/b1/commands")
$PY - "$counters" <<'PYEOF' || fail "counters: $counters"
import json, sys
c = json.loads(sys.argv[1])
assert (c["received"], c["done"], c["malformed"], c["unauthorised"], c["refused"]) == (3, 1, 1, 1, 2), c
PYEOF
[ "$(board_prop 1 State)" = '"Spraying"' ] || fail "board 1 stopped on a refused command"
echo "ok: malformed and unauthorised commands refused and counted"

# The rate law's settings from the machine's topic: every board's dose and threshold change over
# D-Bus; a dose no nozzle can give is refused by the daemon, its reason in the reply, counted as
# failed, and the board sprays on with the dose it had.
mosquitto_sub -h 127.0.0.1 -p "$PORT" -t "weedspray/$MACHINE/b1/reply" -C 3 -W 10 \
  >"$T/replies.txt" &
PIDS+=($!)
replies_pid=$!
sleep 0.5
t0=$(now)
publish "weedspray/$MACHINE/cmd" '{"command":"rate","l_per_ha":180,"id":"r180"}'
publish "weedspray/$MACHINE/cmd" '{"command":"threshold","value":0.25,"id":"t25"}'
for n in "${BOARDS[@]}"; do
  wait_board_prop "$n" TargetRate 180 2
  wait_board_prop "$n" DecisionThreshold 0.25 2
done
echo "ok: rate and threshold on every board $(elapsed_since "$t0") s after the machine's commands"
wait_retained "weedspray/$MACHINE/b2/flow" '"target_l_per_ha":(180[,.]|179\.99)' 3
wait_retained "weedspray/$MACHINE/b2/nozzles" '"decision_threshold":0.25' 3
echo "ok: the new dose and threshold retained on the broker"
publish "weedspray/$MACHINE/b1/cmd" '{"command":"rate","l_per_ha":100000,"id":"too_much"}'
wait "$replies_pid" || fail "no three replies: $(cat "$T/replies.txt")"
grep -q '"id":"r180".*"ok":true' "$T/replies.txt" || fail "replies: $(cat "$T/replies.txt")"
grep -q '"id":"t25".*"ok":true' "$T/replies.txt" || fail "replies: $(cat "$T/replies.txt")"
grep -q '"id":"too_much".*"ok":false.*"reason":"failed"' "$T/replies.txt" ||
  fail "replies: $(cat "$T/replies.txt")"
grep -q "InvalidArgument: 100000 L/ha .*outside the nozzles'" "$T/replies.txt" ||
  fail "the daemon's reason not in the reply: $(cat "$T/replies.txt")"
counters=$(retained "weedspray/$MACHINE/b1/commands")
$PY - "$counters" <<'PYEOF' || fail "counters: $counters"
import json, sys
c = json.loads(sys.argv[1])
assert (c["received"], c["done"], c["failed"], c["refused"]) == (6, 3, 1, 3), c
PYEOF
[ "$(board_prop 1 TargetRate)" = 180 ] || fail "board 1 dose $(board_prop 1 TargetRate) after a refused rate"
[ "$(board_prop 1 State)" = '"Spraying"' ] || fail "board 1 stopped on a refused rate"
echo "ok: a dose no nozzle can give refused by the daemon, in the reply and counted"

# Stop on the machine's topic closes every board's valves.
publish "weedspray/$MACHINE/cmd" '{"command":"stop"}'
for n in "${BOARDS[@]}"; do
  wait_board_closed "$n" 1
done
echo "ok: stop closed every board"

# The machine loses a board: board 1 (fleet.on_board_lost = "stop") stops, board 2 ("continue",
# the default) sprays on. A killed bridge: the broker publishes its last will at once.
publish "weedspray/$MACHINE/cmd" '{"command":"start"}'
for n in "${BOARDS[@]}"; do wait_board_state "$n" Spraying 2; done
kill -KILL "${BRIDGE_PID[3]}"
t0=$(now)
wait_retained "weedspray/$MACHINE/b3/online" '^false$' 3
echo "ok: board 3 lost $(elapsed_since "$t0") s after its bridge was killed"
wait_board_closed 1 1
echo "ok: board 1 stopped $(elapsed_since "$t0") s after board 3 was lost (on_board_lost = stop)"
sleep 1
[ "$(board_prop 2 State)" = '"Spraying"' ] || fail "board 2 (on_board_lost = continue) stopped"
echo "ok: board 2 sprays on (on_board_lost = continue)"
# A killed daemon: its bridge sees the name go and says the board is lost.
kill -KILL "${DAEMON_PID[2]}"
t0=$(now)
wait_retained "weedspray/$MACHINE/b2/online" '^false$' 3
echo "ok: board 2 lost $(elapsed_since "$t0") s after its daemon was killed"
# The broker lost: board 1 (fleet.on_broker_lost = "stop", the default) stops, since the cab can
# no longer stop it; once the broker is back, its bridge reconnects and says it is online.
publish "weedspray/$MACHINE/b1/cmd" '{"command":"start"}'
wait_board_state 1 Spraying 2
kill -KILL "$BROKER_PID"
t0=$(now)
wait_board_closed 1 2
echo "ok: board 1 stopped $(elapsed_since "$t0") s after the broker was lost"
restart_broker
wait_retained "weedspray/$MACHINE/b1/online" '^true$' 15
echo "ok: board 1 back online $(elapsed_since "$t0") s after the broker went"
# A bridge told to stop says goodbye the same way.
kill -TERM "${BRIDGE_PID[1]}"
wait "${BRIDGE_PID[1]}" || fail "weedspray-fleet exit status $?"
wait_retained "weedspray/$MACHINE/b1/online" '^false$' 3
echo "ok: a stopped bridge marks its board offline"
echo "PASS"
