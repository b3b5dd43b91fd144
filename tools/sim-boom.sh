#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# A simulated boom of N boards as one machine (`./dev sim --boom N`): a loopback mosquitto,
# N weedsprayd --sim boards (each on a session bus of its own, 3 nozzles, on the bundled field
# images), a weedspray-fleet bridge each, and the cab page; prints the page's address and the
# broker's, and runs until Ctrl-C, when everything it started is stopped.
#   tools/sim-boom.sh N [BUILD_DIR]     (default build/sim)
# Uses the fleet tests' helpers (tests/integration/fleet/fleet_lib.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
SOURCE=$(pwd)
count=${1:?usage: tools/sim-boom.sh N [BUILD_DIR]}
BUILD=$(realpath "${2:-build/sim}")
[[ "$count" =~ ^[0-9]+$ ]] && ((count >= 1 && count <= 36)) || {
  echo "sim-boom: N is 1..36 boards" >&2
  exit 2
}
. tests/integration/fleet/fleet_lib.sh sim-boom
MACHINE=sim-boom
BOARDS=($(seq 1 "$count"))
CAB_PORT=${CAB_PORT:-8080}

start_broker
for n in "${BOARDS[@]}"; do
  # The bundled images are sparse: make their weeds worth spraying, so the bars move.
  write_board_config "$n" "[spray]" "max_density = 0.3" "decision_threshold = 0.005" \
    "[cab]" "port = $CAB_PORT"
  start_board "$n"
done
for n in "${BOARDS[@]}"; do wait_board_state "$n" Idle 60; done
for n in "${BOARDS[@]}"; do start_bridge "$n"; done
"$BUILD/cab/weedspray-cab" --config "$T/b1/weedspray.toml" >"$T/cab.log" 2>&1 &
PIDS+=($!)
echo "==> $count simulated boards of machine $MACHINE on mosquitto at 127.0.0.1:$PORT"
echo "  the cab page:  http://127.0.0.1:$CAB_PORT/"
echo "  watch:         mosquitto_sub -p $PORT -v -t 'weedspray/$MACHINE/#'"
echo "  start/stop:    mosquitto_pub -p $PORT -t weedspray/$MACHINE/cmd -m '{\"command\":\"start\"}'"
echo "  board N's bus: DBUS_SESSION_BUS_ADDRESS=\$(cat $T/bN/bus.addr) sprayctl --user status"
echo "Ctrl-C stops them all."
wait "${DAEMON_PID[1]}"
