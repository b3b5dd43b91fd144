#!/usr/bin/env bash
# Runs a command on the D-Bus session bus, starting a private one when there is none (root on a
# fresh machine has none), and prints once the line that lets another shell reach it. Used by
# `./dev sim`:  tools/with-session-bus.sh build/sim/daemon/weedsprayd --sim --user ...
# The line names the sprayctl built beside the command.
set -euo pipefail
if [ -z "${DBUS_SESSION_BUS_ADDRESS:-}" ]; then
  socket="${XDG_RUNTIME_DIR:-/tmp}/weedspray-sim-bus"
  rm -f "$socket"
  bus="unix:path=$socket"
  dbus_pid=$(dbus-daemon --session --address="$bus" --fork --print-pid)
  trap 'kill "$dbus_pid" 2>/dev/null || true; rm -f "$socket"' EXIT
  export DBUS_SESSION_BUS_ADDRESS="$bus"
  sprayctl="$(cd "$(dirname "$1")" && pwd)/sprayctl"
  echo "In another shell, steer the simulated sprayer with:"
  echo "  export DBUS_SESSION_BUS_ADDRESS=$bus; $sprayctl --user status"
fi
"$@"
