# SPDX-License-Identifier: Apache-2.0
# shellcheck shell=bash
# Sourced (after private_bus_lib.sh) by the daemon's GNSS test scripts: a real gpsd fed an NMEA
# track by gpsfake, on a free port, in a process group of its own (gpsd goes with it), stopped
# at exit.
#   require_gpsfake; PORT=$(free_port); start_gpsfake PORT LOG ARGS... TRACK; stop_gpsfake
GPSFAKE_PID=

require_gpsfake() {
  [ -x /usr/bin/gpsfake ] && [ -x /usr/sbin/gpsd ] ||
    fail "gpsd and gpsfake are required (apt-get install gpsd gpsd-clients; ./dev deps installs them)"
}

free_port() {
  /usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}

start_gpsfake() {  # start_gpsfake PORT LOG [gpsfake options...] TRACK
  local port=$1 log=$2
  shift 2
  setsid /usr/bin/gpsfake -P "$port" "$@" >"$log" 2>&1 &
  GPSFAKE_PID=$!
}

stop_gpsfake() {
  [ -n "$GPSFAKE_PID" ] && kill -TERM -- "-$GPSFAKE_PID" 2>/dev/null || true
  sleep 0.3
  [ -n "$GPSFAKE_PID" ] && kill -KILL -- "-$GPSFAKE_PID" 2>/dev/null || true
  GPSFAKE_PID=
}
EXIT_HOOKS+=(stop_gpsfake)
