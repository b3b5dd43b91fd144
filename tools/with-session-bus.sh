#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Runs a command on the D-Bus session bus, starting a private one when there is none (root on a
# fresh machine has none), and prints, once the sprayer answers on that bus, the line that lets
# another shell reach it: after the daemon's start-up lines, so it is not lost above them. Used
# by `./dev sim`:  tools/with-session-bus.sh build/sim/daemon/weedsprayd --sim --user ...
# The line names the sprayctl built beside the command.
set -euo pipefail
if [ -n "${DBUS_SESSION_BUS_ADDRESS:-}" ]; then exec "$@"; fi
socket="${XDG_RUNTIME_DIR:-/tmp}/weedspray-sim-bus"
rm -f "$socket"
bus="unix:path=$socket"
dbus_pid=$(dbus-daemon --session --address="$bus" --fork --print-pid)
export DBUS_SESSION_BUS_ADDRESS="$bus"
sprayctl="$(cd "$(dirname "$1")" && pwd)/sprayctl"
sprayer_answers() { # past Starting: its loops run
  busctl --user get-property org.weedspray.Sprayer1 /org/weedspray/Sprayer1 \
    org.weedspray.Sprayer1 State 2>/dev/null | grep -qv '"Starting"'
}
(
  for _ in $(seq 1 600); do
    if sprayer_answers; then
      echo "==> The simulated sprayer is running. In another shell, steer it with:"
      echo "  export DBUS_SESSION_BUS_ADDRESS=$bus; $sprayctl --user status"
      exit 0
    fi
    sleep 0.1
  done
) &
announcer=$!
trap 'kill "$announcer" "$dbus_pid" 2>/dev/null || true; rm -f "$socket"' EXIT
"$@"
