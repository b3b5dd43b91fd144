# Sourced by the daemon's D-Bus test scripts: a scratch folder $T, removed at exit together with
# the daemon and the bus the script started ($DAEMON_PID, $BUS_PID), fail() with the daemon's
# log, and start_private_bus.
# usage: . private_bus_lib.sh NAME   ($T is /tmp/weedspray-NAME-test.XXXXXX)
T=$(mktemp -d "/tmp/weedspray-$1-test.XXXXXX")
DAEMON_PID=
BUS_PID=

cleanup() {
  [ -n "$DAEMON_PID" ] && kill -KILL "$DAEMON_PID" 2>/dev/null || true
  [ -n "$BUS_PID" ] && kill "$BUS_PID" 2>/dev/null || true
  rm -rf "$T"
}
trap cleanup EXIT

fail() {
  echo "FAIL: $*" >&2
  echo "--- daemon log (tail) ---" >&2
  tail -n 40 "$T/daemon.log" >&2 || true
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
