#!/usr/bin/env bash
# Runs a command on the D-Bus session bus, starting a private one when there is none (root on a
# fresh machine has none), and prints once the line that lets another shell reach it. Used by
# `./dev sim`:  tools/with-session-bus.sh build/default/daemon/weedsprayd --sim --user ...
set -euo pipefail
if [ -z "${DBUS_SESSION_BUS_ADDRESS:-}" ]; then
  socket="${XDG_RUNTIME_DIR:-/tmp}/weedspray-sim-bus"
  rm -f "$socket"
  bus="unix:path=$socket"
  dbus_pid=$(dbus-daemon --session --address="$bus" --fork --print-pid)
  trap 'kill "$dbus_pid" 2>/dev/null || true; rm -f "$socket"' EXIT
  export DBUS_SESSION_BUS_ADDRESS="$bus"
  here=$(cd "$(dirname "$0")/.." && pwd)
  echo "In another shell, steer the simulated sprayer with:"
  echo "  export DBUS_SESSION_BUS_ADDRESS=$bus; $here/build/default/daemon/sprayctl --user status"
fi
"$@"
